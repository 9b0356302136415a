// eval_grad: f(wo, wi) and its derivatives with respect to the model's continuous parameters,
// from the same per-element model code instantiated with F = Dual<double, K> (core/dual.h).
//
// For each model of bxdfs/all.h with `GradColumns` (core/bxdf.h), the bound class (bind_model.h's PyModel) gains
//   eval_grad(wo, wi, mode, columns, out_f, out_grad, batch=None) -> (bad wo count, bad wi count)
//     wo, wi       float64 (N or 1, 3) rows, validated and broadcast by Python
//     batch        with per-element parameters (bind_varying.h): the call's batch shape, of which
//                  wo and wi are the N full rows (the planes broadcast to it)
//     columns      list of P gradient columns; a column is a list of (field, channel) pairs whose
//                  partial is seeded with 1 (channel -1: a scalar field; 0..2: one channel of an
//                  RGB field), so a column can tie fields together (Python's "alpha" seeds
//                  alpha_x and alpha_y)
//     out_f        float64 (N, 3); out_grad float64 (N, 3, P): d f_c / d column_p
// and the attribute grad_fields: ((name, 1 or 3), ...) of its differentiable Params fields (those
// templated on the parameter scalar type, core/math.h param_t).
// The model is rebuilt from the Dual-valued Params per call, so derivatives flow through make().
// K is the smallest of 4, 8, 16 that holds P (the padding partials are computed and dropped).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <utility>
#include <vector>

#include "bind_model.h"
#include "bsdfkit/bxdfs/all.h"
#include "bsdfkit/core/dual.h"

namespace bsdfkit::py_bind {

namespace {

using Column = std::vector<std::pair<std::string, int>>;
template <int K> using DualK = Dual<double, K>;

// The Dual-valued Params of Model<DualK<K>> from the double ones, seeded per column.
template <template <typename> class Model, int K>
typename Model<DualK<K>>::Params dual_params(const typename Model<double>::Params &p, const std::vector<Column> &cols) {
    using D = DualK<K>;
    typename Model<D>::Params q;
    std::vector<const void *> src;
    auto &pm = const_cast<typename Model<double>::Params &>(p);
    pm.fields([&](const char *, auto &f) { src.push_back(&f); });
    std::vector<std::vector<bool>> used(cols.size());
    for (size_t c = 0; c < cols.size(); ++c) used[c].assign(cols[c].size(), false);
    size_t idx = 0;
    q.fields([&](const char *name, auto &f) {
        using T = std::decay_t<decltype(f)>;
        const void *s = src[idx++];
        auto seed = [&](int channel, D &x) {
            for (size_t c = 0; c < cols.size(); ++c)
                for (size_t e = 0; e < cols[c].size(); ++e)
                    if (cols[c][e].first == name && cols[c][e].second == channel) {
                        x.d[c] = 1.0;
                        used[c][e] = true;
                    }
        };
        if constexpr (std::is_same_v<T, D>) {
            f = D(*static_cast<const double *>(s));
            seed(-1, f);
        } else if constexpr (std::is_same_v<T, std::array<D, 3>>) {
            const auto &a = *static_cast<const std::array<double, 3> *>(s);
            for (int i = 0; i < 3; ++i) {
                f[size_t(i)] = D(a[size_t(i)]);
                seed(i, f[size_t(i)]);
            }
        } else {
            f = *static_cast<const T *>(s);
        }
    });
    for (size_t c = 0; c < cols.size(); ++c)
        for (size_t e = 0; e < cols[c].size(); ++e)
            if (!used[c][e])
                value_error("params: no differentiable field '" + cols[c][e].first + "' with channel " +
                            std::to_string(cols[c][e].second) + " in " + Model<double>::Name);
    return q;
}

// f and its partials over N pairs (the scalar eval_batch of batch.h with a Dual Float).
template <int SO, int SI, int K, typename Model>
void grad_batch(const Model &m, const double *wo, const double *wi, int64_t n, TransportMode mode, int P,
                double *out_f, double *out_g, int nthreads, BadCounts &bad) {
    using D = DualK<K>;
    parallel_chunks(n, nthreads, kChunk / 4, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0;
        LocalModel<Model> mloc = m;
        for (int64_t i = b; i < e; ++i) {
            Vec3<double> o = load3<double, SO>(wo, i), w = load3<double, SI>(wi, i);
            bo += check_dir(&o);
            bi += check_dir(&w);
            Spectrum<D> v = bsdf_f(mloc, Vec3<D>(o.x, o.y, o.z), Vec3<D>(w.x, w.y, w.z), mode);
            for (int c = 0; c < 3; ++c) {
                out_f[3 * i + c] = v[c].v;
                for (int p = 0; p < P; ++p) out_g[(3 * i + c) * P + p] = v[c].d[p];
            }
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

template <template <typename> class Model, int K>
void run_grad(const typename Model<double>::Params &params, const std::vector<Column> &cols, const double *po,
              int64_t no, const double *pi, int64_t ni, int64_t n, TransportMode md, double *pf, double *pg,
              BadCounts &bad) {
    using M = Model<DualK<K>>;
    M m = M::make(dual_params<Model, K>(params, cols));
    int P = int(cols.size());
    py::gil_scoped_release release;
    int nt = num_threads();
    if (no == n && ni == n) grad_batch<3, 3, K>(m, po, pi, n, md, P, pf, pg, nt, bad);
    else if (no == n) grad_batch<3, 0, K>(m, po, pi, n, md, P, pf, pg, nt, bad);
    else if (ni == n) grad_batch<0, 3, K>(m, po, pi, n, md, P, pf, pg, nt, bad);
    else grad_batch<0, 0, K>(m, po, pi, n, md, P, pf, pg, nt, bad);
}

// Per-element parameters (bind_varying.h): f and its partials with element i's model built from
// element i's Params (Dual-valued, seeded as dual_params seeds them), one model per run of equal
// values; every array full length (n rows).
template <template <typename> class Model, int K>
void run_grad_varying(const VaryingParams<typename Model<double>::Params> &vp, const std::vector<Column> &cols,
                      const double *po, const double *pi, int64_t n, TransportMode md, double *pf, double *pg,
                      BadCounts &bad) {
    using D = DualK<K>;
    using M = Model<D>;
    const int P = int(cols.size());
    dual_params<Model, K>(vp.base, cols);  // checks the column names once (ValueError), with the GIL
    py::gil_scoped_release release;
    parallel_chunks(n, num_threads(), kChunk / 4, [&](int64_t b, int64_t e) {
        int64_t bo = 0, bi = 0;
        for (int64_t i = b; i < e;) {
            int64_t j = i + 1;
            while (j < e && vp.same(i, j)) ++j;
            const M m = M::make(dual_params<Model, K>(vp.at(i), cols));
            for (int64_t r = i; r < j; ++r) {
                Vec3<double> o = load3<double, 3>(po, r), w = load3<double, 3>(pi, r);
                bo += check_dir(&o);
                bi += check_dir(&w);
                Spectrum<D> v = bsdf_f(m, Vec3<D>(o.x, o.y, o.z), Vec3<D>(w.x, w.y, w.z), md);
                for (int c = 0; c < 3; ++c) {
                    pf[3 * r + c] = v[c].v;
                    for (int q = 0; q < P; ++q) pg[(3 * r + c) * P + q] = v[c].d[q];
                }
            }
            i = j;
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

// The differentiable fields of a model: ((name, 1 or 3), ...).
template <template <typename> class Model> py::tuple grad_fields() {
    using D = DualK<1>;
    typename Model<D>::Params q;
    py::list l;
    q.fields([&](const char *name, auto &f) {
        using T = std::decay_t<decltype(f)>;
        if constexpr (std::is_same_v<T, D>) l.append(py::make_tuple(name, 1));
        else if constexpr (std::is_same_v<T, std::array<D, 3>>) l.append(py::make_tuple(name, 3));
    });
    return py::tuple(l);
}

template <template <typename> class Model, int MaxK> void add_eval_grad(py::module_ &) {
    using P = PyModel<Model>;
    py::object cls = py::type::of<P>();
    auto fn = [](const P &self, py::array wo, py::array wi, int mode, std::vector<Column> cols, py::array out_f,
                 py::array out_g, py::object batch) {
        int64_t no, ni, nf, ng;
        const double *po = checked<double>(wo, "wo", {3}, &no), *pi = checked<double>(wi, "wi", {3}, &ni);
        int64_t n = broadcast_rows(no, ni, "wo", "wi");
        int Pn = int(cols.size());
        if (Pn < 1) value_error("params: at least one parameter to differentiate");
        if (Pn > MaxK) value_error("params: at most " + std::to_string(MaxK) + " gradient columns for " +
                                   Model<double>::Name);
        double *pf = checked<double>(out_f, "out_f", {3}, &nf, true);
        double *pg = checked<double>(out_g, "out_grad", {3, Pn}, &ng, true);
        if (nf != n || ng != n) value_error("out: wrong shape");
        TransportMode md = to_mode(mode);
        BadCounts bad;
        if (!self.varying.empty()) {
            // per-element parameters: `batch` is the call's batch shape (the planes broadcast to it),
            // wo and wi its n full rows
            if (batch.is_none()) value_error("eval_grad: a model with per-element parameters needs the batch shape");
            door::Shape shape;
            for (auto d : py::reinterpret_borrow<py::tuple>(batch)) shape.push_back(py::cast<py::ssize_t>(d));
            if (door::prod(shape) != n || no != n || ni != n) value_error("eval_grad: wo, wi must be the batch's rows");
            std::vector<py::array> keep;
            std::vector<ParamPlane> pl = planes_for(self.varying, shape, keep);
            const VaryingParams<typename Model<double>::Params> vp{self.params, pl.data(), int(pl.size())};
            if (Pn <= 4) run_grad_varying<Model, 4>(vp, cols, po, pi, n, md, pf, pg, bad);
            else if constexpr (MaxK > 4) {
                if (Pn <= 8) run_grad_varying<Model, 8>(vp, cols, po, pi, n, md, pf, pg, bad);
                else if constexpr (MaxK > 8) run_grad_varying<Model, 16>(vp, cols, po, pi, n, md, pf, pg, bad);
            }
        } else if (Pn <= 4) run_grad<Model, 4>(self.params, cols, po, no, pi, ni, n, md, pf, pg, bad);
        else if constexpr (MaxK > 4) {
            if (Pn <= 8) run_grad<Model, 8>(self.params, cols, po, no, pi, ni, n, md, pf, pg, bad);
            else if constexpr (MaxK > 8) run_grad<Model, 16>(self.params, cols, po, no, pi, ni, n, md, pf, pg, bad);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.wi.load());
    };
    cls.attr("eval_grad") = py::cpp_function(fn, py::name("eval_grad"), py::is_method(cls),
                                             py::arg("wo"), py::arg("wi"), py::arg("mode"), py::arg("columns"),
                                             py::arg("out_f"), py::arg("out_grad"), py::arg("batch") = py::none());
    cls.attr("grad_fields") = grad_fields<Model>();
    cls.attr("grad_max_columns") = MaxK;
}

// eval_grad for every model of the list that declares GradColumns (core/bxdf.h).
struct GradBinder {
    py::module_ &m;
    template <template <typename> class Model> void apply() {
        constexpr int K = grad_columns<Model<double>>::value;
        if constexpr (K > 0) {
            static_assert(K == 4 || K == 8 || K == 16, "GradColumns: 4, 8 or 16");
            add_eval_grad<Model, K>(m);
        }
    }
};

} // namespace

void bind_grad_models(py::module_ &m) { AllModels::for_each(GradBinder{m}); }

} // namespace bsdfkit::py_bind
