// Shared pieces of the spectral bindings (issue 15): _core.SpectralParam's storage, the
// PySpectral<SM> holder of a spectral adapter's float and double instances with its row-array
// eval / pdf / sample / albedo entries, and bind_spectral_model<SM>(), which binds those entries.
// spectral.cpp binds the pbrt-core, Plastic, Filament and analytic coated adapters; other model
// families bind theirs in their own translation unit with the same helper.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "bind_all.h"
#include "bind_model.h"
#include "bsdfkit/batch_spectral.h"

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

template <template <typename> class SM> struct PySpectral {
    SM<float> m32;
    SM<double> m64;
    std::vector<PySpectralParam> keep;  // owners of the tables the adapters point into

    template <typename F> const SM<F> &get() const {
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

template <template <typename> class SM> inline py::class_<PySpectral<SM>> bind_spectral_model(py::module_ &m, const char *name) {
    using P = PySpectral<SM>;
    py::class_<P> c(m, name);
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
    return c;
}

} // namespace bsdfkit::py_bind
