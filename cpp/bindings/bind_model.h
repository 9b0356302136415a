// Generic pybind11 binding of one model: holds a float and a double instance and dispatches
// on the dtype of the arrays the Python layer has already validated and broadcast. The checks
// here are a second line of defence: a misuse of _core raises, it never reads out of bounds.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "bsdfkit/batch.h"
#include "bsdfkit/core/microfacet.h"

namespace py = pybind11;

namespace bsdfkit::py_bind {

int num_threads();

template <typename F> inline bool is_dtype(const py::array &a) { return a.dtype().is(py::dtype::of<F>()); }

// A batch stopped by the interrupt hook (module.cpp: Ctrl-C) left the Python error set.
inline void raise_if_interrupted() {
    if (PyErr_Occurred()) throw py::error_already_set();
}

[[noreturn]] inline void value_error(const std::string &msg) { throw py::value_error(msg); }

// Checks dtype, C-contiguity and the trailing shape; returns the data pointer.
template <typename T>
T *checked(const py::array &a, const char *name, std::initializer_list<int64_t> tail, int64_t *rows,
           bool writable = false) {
    if (!is_dtype<T>(a)) throw py::type_error(std::string(name) + ": unexpected dtype " + std::string(py::str(a.dtype())));
    if (!(a.flags() & py::array::c_style)) value_error(std::string(name) + ": array must be C-contiguous");
    if (writable && !a.writeable()) value_error(std::string(name) + ": array is read-only");
    if (a.ndim() != int(1 + tail.size())) value_error(std::string(name) + ": wrong number of dimensions");
    int d = 1;
    for (int64_t t : tail)
        if (a.shape(d++) != t) value_error(std::string(name) + ": wrong trailing shape");
    *rows = a.shape(0);
    return static_cast<T *>(const_cast<void *>(a.data()));
}

// Whether two (C-contiguous, already checked) arrays share any byte.
inline bool overlaps(const py::array &a, const py::array &b) {
    if (a.nbytes() == 0 || b.nbytes() == 0) return false;
    auto pa = reinterpret_cast<uintptr_t>(a.data()), pb = reinterpret_cast<uintptr_t>(b.data());
    return pa < pb + uintptr_t(b.nbytes()) && pb < pa + uintptr_t(a.nbytes());
}

inline int64_t broadcast_rows(int64_t a, int64_t b, const char *na, const char *nb) {
    if (a != b && a != 1 && b != 1)
        value_error(std::string(na) + " and " + nb + " have incompatible lengths");
    return a == 1 ? b : a;
}

inline TransportMode to_mode(int m) {
    if (m != 0 && m != 1) value_error("mode: must be TransportMode.Radiance (0) or Importance (1)");
    return TransportMode(m);
}
inline uint8_t to_sflags(int s) {
    if (s < 0 || s > 3) value_error("sample_flags: must be a ReflTrans value in 0..3");
    return uint8_t(s);
}

// One bound model (core/bxdf.h): both precisions, built from one Params (kept for `params`).
template <template <typename> class Model> struct PyModel {
    Model<float> m32;
    Model<double> m64;
    typename Model<double>::Params params;

    template <typename F> const Model<F> &get() const {
        if constexpr (std::is_same_v<F, float>) return m32; else return m64;
    }

    template <typename F>
    py::tuple eval_t(const py::array &wo, const py::array &wi, int mode, py::array &out) const {
        int64_t no, ni, nout;
        const F *po = checked<F>(wo, "wo", {3}, &no), *pi = checked<F>(wi, "wi", {3}, &ni);
        F *pout = checked<F>(out, "out", {3}, &nout, true);
        int64_t n = broadcast_rows(no, ni, "wo", "wi");
        if (nout != n) value_error("out: wrong shape");
        TransportMode md = to_mode(mode);
        BadCounts bad;
        {
            py::gil_scoped_release release;
            const Model<F> &m = get<F>();
            int nt = num_threads();
            if (no == n && ni == n) eval_batch<3, 3>(m, po, pi, n, md, pout, nt, bad);
            else if (no == n) eval_batch<3, 0>(m, po, pi, n, md, pout, nt, bad);
            else if (ni == n) eval_batch<0, 3>(m, po, pi, n, md, pout, nt, bad);
            else eval_batch<0, 0>(m, po, pi, n, md, pout, nt, bad);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.wi.load());
    }

    template <typename F>
    py::tuple pdf_t(const py::array &wo, const py::array &wi, int mode, int sf, py::array &out) const {
        int64_t no, ni, nout;
        const F *po = checked<F>(wo, "wo", {3}, &no), *pi = checked<F>(wi, "wi", {3}, &ni);
        F *pout = checked<F>(out, "out", {}, &nout, true);
        int64_t n = broadcast_rows(no, ni, "wo", "wi");
        if (nout != n) value_error("out: wrong shape");
        TransportMode md = to_mode(mode);
        uint8_t s = to_sflags(sf);
        BadCounts bad;
        {
            py::gil_scoped_release release;
            const Model<F> &m = get<F>();
            int nt = num_threads();
            if (no == n && ni == n) pdf_batch<3, 3>(m, po, pi, n, md, s, pout, nt, bad);
            else if (no == n) pdf_batch<3, 0>(m, po, pi, n, md, s, pout, nt, bad);
            else if (ni == n) pdf_batch<0, 3>(m, po, pi, n, md, s, pout, nt, bad);
            else pdf_batch<0, 0>(m, po, pi, n, md, s, pout, nt, bad);
        }
        raise_if_interrupted();
        return py::make_tuple(bad.wo.load(), bad.wi.load());
    }

    template <typename F>
    int64_t sample_t(const py::array &wo, const py::array &uc, const py::array &u, int mode, int sf,
                     py::array &wi_out, py::array &f_out, py::array &pdf_out, py::array &flags_out,
                     py::array &eta_out, py::array &valid_out, py::array &prop_out) const {
        int64_t no, nuc, nu, r;
        const F *po = checked<F>(wo, "wo", {3}, &no);
        const F *puc = checked<F>(uc, "uc", {}, &nuc);
        const F *pu = checked<F>(u, "u", {2}, &nu);
        if (nuc != nu) value_error("uc and u must have the same length");
        int64_t n = broadcast_rows(no, nuc, "wo", "uc");
        if (nuc != n) value_error("uc: wrong length");
        SampleOut<F> o;
        o.wi = checked<F>(wi_out, "wi", {3}, &r, true); if (r != n) value_error("wi: wrong shape");
        o.f = checked<F>(f_out, "f", {3}, &r, true); if (r != n) value_error("f: wrong shape");
        o.pdf = checked<F>(pdf_out, "pdf", {}, &r, true); if (r != n) value_error("pdf: wrong shape");
        o.flags = checked<uint8_t>(flags_out, "flags", {}, &r, true); if (r != n) value_error("flags: wrong shape");
        o.eta = checked<F>(eta_out, "eta", {}, &r, true); if (r != n) value_error("eta: wrong shape");
        o.valid = checked<bool>(valid_out, "valid", {}, &r, true); if (r != n) value_error("valid: wrong shape");
        o.proportional = checked<bool>(prop_out, "pdf_is_proportional", {}, &r, true);
        if (r != n) value_error("pdf_is_proportional: wrong shape");
        // sample_batch's pointers are restrict: no output may overlap an input or another output.
        {
            const py::array *arrs[] = {&wo, &uc, &u, &wi_out, &f_out, &pdf_out, &flags_out, &eta_out, &valid_out, &prop_out};
            for (int a = 3; a < 10; ++a)
                for (int c = 0; c < a; ++c)
                    if (overlaps(*arrs[a], *arrs[c])) value_error("sample: output arrays must not overlap the inputs or each other");
        }
        TransportMode md = to_mode(mode);
        uint8_t s = to_sflags(sf);
        BadCounts bad;
        {
            py::gil_scoped_release release;
            const Model<F> &m = get<F>();
            if (no == n) sample_batch<3>(m, po, puc, pu, n, md, s, o, num_threads(), bad);
            else sample_batch<0>(m, po, puc, pu, n, md, s, o, num_threads(), bad);
        }
        raise_if_interrupted();
        return bad.wo.load();
    }

    template <typename F>
    int64_t albedo_t(const py::array &wo, int64_t n_samples, uint64_t seed, int mode, py::array &out) const {
        int64_t no, nout;
        const F *po = checked<F>(wo, "wo", {3}, &no);
        F *pout = checked<F>(out, "out", {3}, &nout, true);
        if (nout != no) value_error("out: wrong shape");
        if (n_samples <= 0) value_error("n_samples: must be positive");
        TransportMode md = to_mode(mode);
        BadCounts bad;
        {
            py::gil_scoped_release release;
            albedo_batch(get<F>(), po, no, n_samples, seed, md, pout, num_threads(), bad);
        }
        raise_if_interrupted();
        return bad.wo.load();
    }
};

template <template <typename> class Model>
py::class_<PyModel<Model>> bind_model(py::module_ &m, const char *name) {
    using P = PyModel<Model>;
    py::class_<P> c(m, name);
    c.def("eval", [](const P &self, py::array wo, py::array wi, int mode, py::array out) {
         return is_dtype<float>(wo) ? self.template eval_t<float>(wo, wi, mode, out)
                                    : self.template eval_t<double>(wo, wi, mode, out);
     })
        .def("pdf", [](const P &self, py::array wo, py::array wi, int mode, int sf, py::array out) {
            return is_dtype<float>(wo) ? self.template pdf_t<float>(wo, wi, mode, sf, out)
                                       : self.template pdf_t<double>(wo, wi, mode, sf, out);
        })
        .def("sample", [](const P &self, py::array wo, py::array uc, py::array u, int mode, int sf, py::array wi,
                          py::array f, py::array pdf, py::array flags, py::array eta, py::array valid,
                          py::array prop) {
            return is_dtype<float>(wo)
                       ? self.template sample_t<float>(wo, uc, u, mode, sf, wi, f, pdf, flags, eta, valid, prop)
                       : self.template sample_t<double>(wo, uc, u, mode, sf, wi, f, pdf, flags, eta, valid, prop);
        })
        .def("albedo", [](const P &self, py::array wo, int64_t n, uint64_t seed, int mode, py::array out) {
            return is_dtype<float>(wo) ? self.template albedo_t<float>(wo, n, seed, mode, out)
                                       : self.template albedo_t<double>(wo, n, seed, mode, out);
        })
        .def_property_readonly("flags", [](const P &self) { return int(self.m64.flags()); });
    return c;
}

} // namespace bsdfkit::py_bind
