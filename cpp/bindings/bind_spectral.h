// The spectral forms' bindings (issue 15; core/bxdf.h `Spectral`): _core.SpectralParam's storage,
// the PySpectral<Model> holder of a form's float and double instances with its row-array
// eval / pdf / sample / albedo entries, and bind_spectral_form<Model>(), which bind_all.h calls
// for every model of the list that declares a spectral form (in that model family's unit).
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "bind_model.h"
#include "bind_params.h"
#include "bsdfkit/spectral/all.h"

namespace bsdfkit::py_bind {


// A table's storage: nodes, values and the per-nm segment index (core/spectral.h).
struct TableData {
    std::vector<double> x, v, slope;
    std::vector<int32_t> first;
};

// A SpectralParam plus the table it points into (shared: copies keep it alive).
struct PySpectralParam {
    SpectralParam p;
    std::shared_ptr<TableData> table;
};

inline std::string kind_name(SpectralParam::Kind k) {
    return k == SpectralParam::Constant ? "constant" : k == SpectralParam::Sigmoid ? "sigmoid" : "table";
}

// A bound handle of a shared immutable table (the spectra of a measured model). (Not a bare
// std::shared_ptr: pybind11 reads a shared_ptr<T> argument as the holder of a bound T.)
template <typename T> struct TableHandle {
    std::shared_ptr<const T> p;
    TableHandle(std::shared_ptr<const T> q) : p(std::move(q)) {}
    const T *operator->() const { return p.get(); }
    explicit operator bool() const { return bool(p); }
};

// The named inputs of a spectral form's make() (core/bxdf.h `Spectral`): the `spectral` dict of
// the constructor, {field: SpectralParam} for each of the form's kFields plus the few extra
// inputs it reads (flags, numbers, tables). A missing or unknown name, or a value of the wrong
// type, raises TypeError naming it. The SpectralParams and tables are read in place: the bound
// object keeps the dict (and so them) alive.
struct SpectralKw {
    py::dict d;
    std::string what;  // "<Name>Spectral"
    mutable std::vector<std::string> used;

    py::handle get(const char *name) const {
        if (!d.contains(name)) throw py::type_error(what + ": missing spectral input '" + name + "'");
        used.emplace_back(name);
        return d[name];
    }
    const SpectralParam &param(const char *name) const {
        py::handle h = get(name);
        if (!py::isinstance<PySpectralParam>(h))
            throw py::type_error(what + "." + name + ": expected a _core.SpectralParam, got " + bind_detail::type_name(h));
        return h.cast<const PySpectralParam &>().p;
    }
    bool flag(const char *name) const {
        bool v = false;
        bind_detail::from_py(get(name), v, what + "." + name);
        return v;
    }
    double number(const char *name) const {
        double v = 0;
        bind_detail::from_py(get(name), v, what + "." + name);
        return v;
    }
    template <typename T> const T &table(const char *name) const {
        py::handle h = get(name);
        if (!py::isinstance<TableHandle<T>>(h)) throw py::type_error(what + "." + name + ": wrong table type, got " + bind_detail::type_name(h));
        const TableHandle<T> &t = h.cast<const TableHandle<T> &>();
        if (!t) throw py::value_error(what + "." + name + ": must not be empty");
        return *t.p;
    }
    void check_all_used() const {
        for (auto item : d) {
            std::string k = py::str(item.first);
            if (std::find(used.begin(), used.end(), k) == used.end())
                throw py::type_error(what + ": unexpected spectral input '" + k + "'");
        }
    }
};

// A form's spectral fields: its kFields, or spectral_fields() when the form derives them (the
// generic ColourSpectral walks the Params).
template <typename S, typename = void> struct has_fields_fn : std::false_type {};
template <typename S> struct has_fields_fn<S, std::void_t<decltype(S::spectral_fields())>> : std::true_type {};
template <typename S> std::vector<SpectralField> spectral_fields_of() {
    if constexpr (has_fields_fn<S>::value) return S::spectral_fields();
    else return std::vector<SpectralField>(std::begin(S::kFields), std::end(S::kFields));
}

// The bound spectral form of a model (_core.<Name>Spectral): its float and double instances
// and the Python objects they point into.
template <template <typename> class Model> struct PySpectral {
    using S32 = typename Model<float>::Spectral;
    using S64 = typename Model<double>::Spectral;
    S32 m32;
    S64 m64;
    py::object keep;  // the constructor's spectral inputs and keyword arguments

    template <typename F> const auto &get() const {
        if constexpr (std::is_same_v<F, float>) return m32; else return m64;
    }

    // Rows of `a` (n, or 1 = broadcast) with trailing shape `tail`; its stride in elements.
    template <typename T>
    static const T *rows(const py::array &a, const char *name, int64_t tail, int64_t n, int64_t *stride) {
        int64_t r;
        const T *p = checked<T>(a, name, {tail}, &r);
        if (r != n && r != 1) value_error(std::string(name) + ": wrong number of rows");
        *stride = r == n && n != 1 ? tail : (r == 1 ? 0 : tail);
        return p;
    }

    template <typename F>
    py::tuple eval_t(const py::array &wo, const py::array &wi, const py::array &lam, int mode, py::array &out,
                     bool packets) const {
        int64_t n, so, si, sl;
        F *po = checked<F>(out, "out", {4}, &n, true);
        const F *pwo = rows<F>(wo, "wo", 3, n, &so), *pwi = rows<F>(wi, "wi", 3, n, &si);
        const double *pl = rows<double>(lam, "wavelengths", 4, n, &sl);
        check_out_no_overlap(out, wo, wi, &lam);
        TransportMode md = to_mode(mode);
        SpectralBadCounts bad;
        {
            py::gil_scoped_release release;
            eval_spectral_batch(get<F>(), pwo, so, pwi, si, pl, sl, n, md, po, num_threads(), bad, packets);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.wi.load(), bad.lam.load());
    }

    template <typename F>
    py::tuple pdf_t(const py::array &wo, const py::array &wi, const py::array &lam, int mode, int sf,
                    py::array &out, bool packets) const {
        int64_t n, so, si, sl;
        F *po = checked<F>(out, "out", {}, &n, true);
        const F *pwo = rows<F>(wo, "wo", 3, n, &so), *pwi = rows<F>(wi, "wi", 3, n, &si);
        const double *pl = rows<double>(lam, "wavelengths", 4, n, &sl);
        check_out_no_overlap(out, wo, wi, &lam);
        TransportMode md = to_mode(mode);
        uint8_t s = to_sflags(sf);
        SpectralBadCounts bad;
        {
            py::gil_scoped_release release;
            pdf_spectral_batch(get<F>(), pwo, so, pwi, si, pl, sl, n, md, s, po, num_threads(), bad, packets);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.wi.load(), bad.lam.load());
    }

    template <typename F>
    py::tuple sample_t(const py::array &wo, const py::array &uc, const py::array &u, const py::array &lam, int mode,
                       int sf, py::array &wi_out, py::array &f_out, py::array &pdf_out, py::array &flags_out,
                       py::array &eta_out, py::array &valid_out, py::array &prop_out, py::array &term_out,
                       bool packets) const {
        int64_t n, nu, r, so, sl;
        const F *puc = checked<F>(uc, "uc", {}, &n);
        const F *pu = checked<F>(u, "u", {2}, &nu);
        if (nu != n) value_error("uc and u must have the same length");
        const F *pwo = rows<F>(wo, "wo", 3, n, &so);
        const double *pl = rows<double>(lam, "wavelengths", 4, n, &sl);
        SpectralSampleOut<F> o;
        checked_sample_out<kSpectralN, F>(n, o, wi_out, f_out, pdf_out, flags_out, eta_out, valid_out, prop_out);
        o.terminated = checked<bool>(term_out, "terminated", {}, &r, true);
        if (r != n) value_error("terminated: wrong shape");
        check_sample_no_overlap({&wo, &uc, &u, &lam, &wi_out, &f_out, &pdf_out, &flags_out, &eta_out, &valid_out,
                                 &prop_out, &term_out}, 4);
        TransportMode md = to_mode(mode);
        uint8_t s = to_sflags(sf);
        SpectralBadCounts bad;
        {
            py::gil_scoped_release release;
            sample_spectral_batch(get<F>(), pwo, so, puc, pu, pl, sl, n, md, s, o, num_threads(), bad, packets);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.uc.load(), bad.u.load(), bad.lam.load());
    }

    template <typename F>
    py::tuple albedo_t(const py::array &wo, const py::array &lam, int64_t n_samples, uint64_t seed, int mode,
                       py::array &out) const {
        int64_t n, no, sl;
        F *po = checked<F>(out, "out", {4}, &n, true);
        const F *pwo = checked<F>(wo, "wo", {3}, &no);
        if (no != n) value_error("wo: wrong number of rows");
        const double *pl = rows<double>(lam, "wavelengths", 4, n, &sl);
        if (n_samples <= 0) value_error("n_samples: must be positive");
        TransportMode md = to_mode(mode);
        SpectralBadCounts bad;
        {
            py::gil_scoped_release release;
            albedo_spectral_batch(get<F>(), pwo, n, pl, sl, n_samples, seed, md, po, num_threads(), bad);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.lam.load());
    }
};

// Binds _core.<Name>Spectral, the spectral form of Model, with its one constructor:
//   <Name>Spectral(spectral: dict, **params)
// params: the model's keyword arguments (its RGB Params, bind_all.h: what stays
// wavelength-independent, as the RGB projection); spectral: the form's named inputs (SpectralKw).
template <template <typename> class Model> inline void bind_spectral_form(py::module_ &m) {
    using P = PySpectral<Model>;
    using Params = typename Model<double>::Params;
    const std::string name = std::string(Model<double>::Name) + "Spectral";
    py::class_<P> c(m, name.c_str());
    c.def(py::init([name](const py::dict &spectral, const py::kwargs &kw) {
             Params p = bind_detail::params_from_kwargs<Params>(Model<double>::Name, py::args(), kw);
             SpectralKw a{spectral, name, {}};
             P o;
             o.m32 = P::S32::make(p, a);
             o.m64 = P::S64::make(p, a);
             a.check_all_used();
             o.keep = py::make_tuple(py::dict(spectral), kw);  // a copy: the caller may change its dict
             return o;
         }),
         py::arg("spectral"),
         ("Spectral form of " + std::string(Model<double>::Name) +
          " (core/bxdf.h): spectral = {field: SpectralParam, ...} for spectral_fields plus its extra inputs; "
          "keyword arguments: the model's (their colours as the RGB projection).").c_str());
    py::list fields;
    for (const SpectralField &f : spectral_fields_of<typename P::S64>()) fields.append(py::make_tuple(f.name, f.kind));
    c.attr("spectral_fields") = py::tuple(fields);
    // packets=False: the scalar per-element path (the packet path's reference in the tests).
    c.def("eval", [](const P &self, py::array wo, py::array wi, py::array lam, int mode, py::array out, bool packets) {
         return is_dtype<float>(out) ? self.template eval_t<float>(wo, wi, lam, mode, out, packets)
                                     : self.template eval_t<double>(wo, wi, lam, mode, out, packets);
     }, py::arg("wo"), py::arg("wi"), py::arg("wavelengths"), py::arg("mode"), py::arg("out"), py::arg("packets") = true)
        .def("pdf", [](const P &self, py::array wo, py::array wi, py::array lam, int mode, int sf, py::array out,
                       bool packets) {
            return is_dtype<float>(out) ? self.template pdf_t<float>(wo, wi, lam, mode, sf, out, packets)
                                        : self.template pdf_t<double>(wo, wi, lam, mode, sf, out, packets);
        }, py::arg("wo"), py::arg("wi"), py::arg("wavelengths"), py::arg("mode"), py::arg("sample_flags"), py::arg("out"),
           py::arg("packets") = true)
        .def("sample", [](const P &self, py::array wo, py::array uc, py::array u, py::array lam, int mode, int sf,
                          py::array wi, py::array f, py::array pdf, py::array flags, py::array eta, py::array valid,
                          py::array prop, py::array term, bool packets) {
            return is_dtype<float>(f)
                       ? self.template sample_t<float>(wo, uc, u, lam, mode, sf, wi, f, pdf, flags, eta, valid, prop, term, packets)
                       : self.template sample_t<double>(wo, uc, u, lam, mode, sf, wi, f, pdf, flags, eta, valid, prop, term, packets);
        }, py::arg("wo"), py::arg("uc"), py::arg("u"), py::arg("wavelengths"), py::arg("mode"), py::arg("sample_flags"),
           py::arg("wi"), py::arg("f"), py::arg("pdf"), py::arg("flags"), py::arg("eta"), py::arg("valid"),
           py::arg("pdf_is_proportional"), py::arg("terminated"), py::arg("packets") = true)
        .def("albedo", [](const P &self, py::array wo, py::array lam, int64_t n, uint64_t seed, int mode, py::array out) {
            return is_dtype<float>(out) ? self.template albedo_t<float>(wo, lam, n, seed, mode, out)
                                        : self.template albedo_t<double>(wo, lam, n, seed, mode, out);
        })
        .def_property_readonly("dispersive", [](const P &self) { return self.m64.dispersive(); });
}

} // namespace bsdfkit::py_bind
