// Generic pybind11 binding of one model: holds a float and a double instance and dispatches on
// the dtype of the arrays. One door per operation: eval / pdf / sample / albedo each take the
// user's arguments as given. Plain arguments (Plain below: float32 / float64 ndarrays in the
// layouts the kernels read) go straight to the kernels: the shape and dtype decisions, the output
// allocation, the kernel (which counts non-unit directions and out-of-range uniforms) and the
// ValueError for a bad value. Anything else (Python scalars, lists, other dtypes, broadcasting
// shapes, n= / seed=) is converted with numpy's C API in the same call (door.h), where every
// argument error is worded once, naming the argument, and then runs the same kernels. The
// Python layer (models/base.py) only dispatches (spectral, Dask).
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "bind_varying.h"
#include "block_cache.h"
#include "door.h"
#include "bsdfkit/batch.h"
#include "bsdfkit/core/microfacet.h"

namespace py = pybind11;

namespace bsdfkit::py_bind {

int num_threads();

// A numpy descriptor's byte-order character names this machine's order ('=' native, '|' not
// applicable, or the explicit '<' / '>' that is native here).
inline bool native_byte_order(char bo) {
    constexpr char native = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ ? '<' : '>';
    return bo == '=' || bo == '|' || bo == native;
}

// The identity test is the fast path; an equal descriptor that is another object (an array that
// came through pickle, e.g. a Dask block) is accepted by its type number and byte order
// (numpy's PyArray_EquivTypes would also accept a byte-swapped array, which the kernels would
// read as garbage).
template <typename F> inline bool is_dtype(const py::array &a) {
    py::dtype want = py::dtype::of<F>();
    py::dtype got = a.dtype();
    return got.is(want) || (got.num() == want.num() && native_byte_order(got.byteorder()));
}

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

// The outputs every sample entry writes (wi, f with NC channels: 3 RGB, 4 spectral, pdf, flags,
// eta, valid, pdf_is_proportional), each checked for dtype, layout and n rows, into Out's pointers
// (SampleOut<F>, or SpectralSampleOut<F> whose further outputs the caller adds).
template <int NC, typename F, typename Out>
inline void checked_sample_out(int64_t n, Out &o, const py::array &wi, const py::array &f, const py::array &pdf,
                               const py::array &flags, const py::array &eta, const py::array &valid,
                               const py::array &prop) {
    int64_t r;
    auto rows_n = [&](const char *name) { if (r != n) value_error(std::string(name) + ": wrong shape"); };
    o.wi = checked<F>(wi, "wi", {3}, &r, true); rows_n("wi");
    o.f = checked<F>(f, "f", {NC}, &r, true); rows_n("f");
    o.pdf = checked<F>(pdf, "pdf", {}, &r, true); rows_n("pdf");
    o.flags = checked<uint8_t>(flags, "flags", {}, &r, true); rows_n("flags");
    o.eta = checked<F>(eta, "eta", {}, &r, true); rows_n("eta");
    o.valid = checked<bool>(valid, "valid", {}, &r, true); rows_n("valid");
    o.proportional = checked<bool>(prop, "pdf_is_proportional", {}, &r, true); rows_n("pdf_is_proportional");
}

// The sample kernels' pointers are restrict: no output may overlap an input or another output.
// arrs: the inputs (the first n_in), then the outputs.
inline void check_sample_no_overlap(std::initializer_list<const py::array *> arrs, size_t n_in) {
    const py::array *const *a = arrs.begin();
    for (size_t i = n_in; i < arrs.size(); ++i)
        for (size_t c = 0; c < i; ++c)
            if (overlaps(*a[i], *a[c])) value_error("sample: output arrays must not overlap the inputs or each other");
}

// eval's and pdf's out= may not share memory with wo or wi (nor, spectral, the wavelengths): the
// kernels' pointers are restrict and they write a packet's rows before reading the next packet's
// (an out= one row past wo's start read rows the kernel had already overwritten).
inline void check_out_no_overlap(const py::array &out, const py::array &wo, const py::array &wi,
                                 const py::array *lam = nullptr) {
    if (overlaps(out, wo) || overlaps(out, wi)) value_error("out: must not overlap wo or wi");
    if (lam && overlaps(out, *lam)) value_error("out: must not overlap wavelengths");
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


// Messages of the values the kernels count (the Python layer words the same, base.py _raise_bad).
inline std::string bad_message(const char *name, int64_t count) {
    if (name[0] == 'u')  // uc, u
        return std::string(name) + ": " + std::to_string(count) +
               " sample value(s) are outside [0, 1] or NaN (uniforms must lie in [0, 1])";
    return std::string(name) + ": " + std::to_string(count) +
           " direction(s) are not finite unit vectors (|w|^2 must equal 1 within 1e-4; normalize them first)";
}
inline void raise_bad(const BadCounts &bad, bool dirs_wi, bool uniforms) {
    int64_t bo = bad.wo.load(), bi = dirs_wi ? bad.wi.load() : 0;
    int64_t buc = uniforms ? bad.uc.load() : 0, bu = uniforms ? bad.u.load() : 0;
    if (bo) value_error(bad_message("wo", bo));
    if (bi) value_error(bad_message("wi", bi));
    if (buc) value_error(bad_message("uc", buc));
    if (bu) value_error(bad_message("u", bu));
}

// ---- "plain" arguments of the door's fast path (PyModel::eval / pdf / sample / albedo) ----
// An argument is plain when it is exactly a numpy.ndarray of float32 or float64, C-contiguous
// (or (N, 3) / (N, 2) Fortran-order planes where the kernels read them), with the expected
// trailing axis. The door converts anything else first (door.h). Reads the array struct
// directly: a call on one direction pair should cost about a microsecond.
struct Plain {
    PyObject *obj = nullptr;
    int type = 0;  // npy type number
    int ndim = 0;
    const py::ssize_t *shape = nullptr;
    void *data = nullptr;
    int64_t rows = 1;  // product of the leading axes (all axes when tail == 0)
    bool writeable = false;
    bool planes = false;  // an (N, last) Fortran-order array (not also C-contiguous): `last` planes of N
};

// fortran: also accept a 2-D (N, last) Fortran-order array (planes; a.planes set). Directions
// and eval's out: the component planes the packet kernels read without transposition (batch.h).
inline bool plain(py::handle h, int tail, py::ssize_t last, Plain &a, bool fortran = false) {
    auto &api = py::detail::npy_api::get();
    if (Py_TYPE(h.ptr()) != api.PyArray_Type_) return false;
    auto *p = py::detail::array_proxy(h.ptr());
    a.planes = false;
    if (!(p->flags & py::detail::npy_api::NPY_ARRAY_C_CONTIGUOUS_)) {
        if (!fortran || tail != 1 || p->nd != 2 || !(p->flags & py::detail::npy_api::NPY_ARRAY_F_CONTIGUOUS_))
            return false;
        a.planes = true;
    }
    a.type = py::detail::array_descriptor_proxy(p->descr)->type_num;
    if (a.type != py::detail::npy_api::NPY_FLOAT_ && a.type != py::detail::npy_api::NPY_DOUBLE_) return false;
    if (!native_byte_order(py::detail::array_descriptor_proxy(p->descr)->byteorder)) return false;
    a.ndim = p->nd;
    if (a.ndim < tail || (tail && p->dimensions[a.ndim - 1] != last)) return false;
    a.obj = h.ptr();
    a.shape = p->dimensions;
    a.data = p->data;
    a.writeable = (p->flags & py::detail::npy_api::NPY_ARRAY_WRITEABLE_) != 0;
    a.rows = 1;
    for (int d = 0; d < a.ndim - tail; ++d) a.rows *= a.shape[d];
    return true;
}

// numpy broadcasting of two batch shapes when they are equal or one of them is a single item
// that broadcasts without adding axes; false otherwise (the general path broadcasts the rest).
// On success `big` is the side whose batch shape is the result.
inline bool simple_batch(const Plain &a, int ta, const Plain &b, int tb, const Plain *&big) {
    int na = a.ndim - ta, nb = b.ndim - tb;
    if (na == nb && std::equal(a.shape, a.shape + na, b.shape)) { big = &a; return true; }
    if (a.rows == 1 && na <= nb) { big = &b; return true; }
    if (b.rows == 1 && nb <= na) { big = &a; return true; }
    return false;
}

inline std::vector<py::ssize_t> batch_shape(const Plain &a, int tail, std::initializer_list<py::ssize_t> extra) {
    std::vector<py::ssize_t> s(a.shape, a.shape + (a.ndim - tail));
    s.insert(s.end(), extra);
    return s;
}

// A plain int (or IntEnum) in [lo, hi], or -1.
inline int small_int(py::handle h, int lo, int hi) {
    if (!PyLong_Check(h.ptr())) return -1;
    long v = PyLong_AsLong(h.ptr());
    if (v == -1 && PyErr_Occurred()) { PyErr_Clear(); return -1; }
    return (v < lo || v > hi) ? -1 : int(v);
}

// The data of a plain output (eval / pdf / sample's out=): exactly a numpy.ndarray of npy type `type`,
// C-contiguous, writeable, in native byte order, of exactly `shape`; else nullptr.
inline void *plain_out_data(py::handle h, int type, const std::vector<py::ssize_t> &shape) {
    auto &api = py::detail::npy_api::get();
    if (Py_TYPE(h.ptr()) != api.PyArray_Type_) return nullptr;
    auto *p = py::detail::array_proxy(h.ptr());
    constexpr int need = py::detail::npy_api::NPY_ARRAY_C_CONTIGUOUS_ | py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    auto *d = py::detail::array_descriptor_proxy(p->descr);
    if ((p->flags & need) != need || d->type_num != type || !native_byte_order(d->byteorder) ||
        p->nd != int(shape.size()) || !std::equal(shape.begin(), shape.end(), p->dimensions))
        return nullptr;
    return p->data;
}

// A plain output array of the given type and exact shape, writeable, or false. planes: set when
// it is an (N, 3) Fortran-order array (accepted only when `planes` is given); C order otherwise,
// as plain_out_data.
inline bool plain_out(py::handle h, int type, const std::vector<py::ssize_t> &shape, bool *planes = nullptr) {
    if (planes == nullptr || shape.size() != 2) {
        if (planes) *planes = false;
        return plain_out_data(h, type, shape) != nullptr;
    }
    Plain o;
    if (!plain(h, 1, shape[1], o, true) || o.type != type || !o.writeable || o.ndim != 2) return false;
    *planes = o.planes;
    return std::equal(shape.begin(), shape.end(), o.shape);
}

// The packet kernels' view of a plain direction argument of a call over n pairs (batch.h Dirs).
template <typename F> inline Dirs<F> dirs_of_plain(const Plain &a, int64_t n) {
    const F *p = static_cast<const F *>(a.data);
    if (a.rows != n) return {p, DirLayout::One, 0};
    return {p, a.planes ? DirLayout::Planes : DirLayout::Rows, a.planes ? n : 0};
}

// A C-order result array of `shape` for eval / pdf: from 1 MiB on a view of a BlockCache block
// (64-byte aligned, so that a kernel that streams its outputs can, batch.h; its pages kept warm
// between calls, as the sample block's), else a numpy array.
template <typename F> inline py::array result_array(const std::vector<py::ssize_t> &shape) {
    size_t count = 1;
    for (py::ssize_t s : shape) count *= size_t(s);
    const size_t bytes = count * sizeof(F);
    if (bytes < BlockCache::kMinBytes) return py::array_t<F>(shape);
    void *data = nullptr;
    py::capsule blk = cached_block(bytes, &data);  // 2 MiB aligned
    return py::array(py::dtype::of<F>(), shape, data, blk);
}

// One allocation for the seven sample outputs, the arrays views of it (in this order: wi, f,
// pdf, eta as F, 64-byte aligned; flags, valid, pdf_is_proportional as bytes). A small block is
// a numpy array; from 1 MiB on it comes from BlockCache (block_cache.h), which keeps the pages of
// recently freed blocks instead of faulting fresh ones in on every call. A new block is left
// untouched (huge pages requested), so the sample kernel's worker threads first-touch it.
template <typename F> struct SampleBlock {
    py::tuple arrays;  // wi, f, pdf, flags, eta, valid, pdf_is_proportional (SampleResult order)
    SampleOut<F> out;
    SampleBlock(const std::vector<py::ssize_t> &batch, int64_t n) {
        auto pad = [](int64_t b) { return (b + 63) & ~int64_t(63); };
        const int64_t s = int64_t(sizeof(F));
        int64_t o_wi = 0, o_f = pad(o_wi + 3 * n * s), o_pdf = pad(o_f + 3 * n * s), o_eta = pad(o_pdf + n * s),
                o_fl = pad(o_eta + n * s), o_va = o_fl + n, o_pr = o_va + n, total = o_pr + n + 64;
        py::object blk;
        void *data = nullptr;
        if (size_t(total) >= BlockCache::kMinBytes) {
            blk = cached_block(size_t(total), &data);
        } else {
            py::array_t<uint8_t> a(total);
            data = a.mutable_data();
            blk = std::move(a);
        }
        auto base = reinterpret_cast<uintptr_t>(data);
        uintptr_t start = (base + 63) & ~uintptr_t(63);
        auto at = [&](int64_t off) { return reinterpret_cast<void *>(start + uintptr_t(off)); };
        std::vector<py::ssize_t> b3(batch);
        b3.push_back(3);
        auto view = [&](py::dtype dt, const std::vector<py::ssize_t> &shape, void *p) {
            return py::array(dt, shape, p, blk);  // a view: its base keeps the block alive
        };
        py::array wi = view(py::dtype::of<F>(), b3, at(o_wi)), f = view(py::dtype::of<F>(), b3, at(o_f)),
                  pdf = view(py::dtype::of<F>(), batch, at(o_pdf)), eta = view(py::dtype::of<F>(), batch, at(o_eta)),
                  fl = view(py::dtype::of<uint8_t>(), batch, at(o_fl)), va = view(py::dtype::of<bool>(), batch, at(o_va)),
                  pr = view(py::dtype::of<bool>(), batch, at(o_pr));
        out.wi = static_cast<F *>(at(o_wi));
        out.f = static_cast<F *>(at(o_f));
        out.pdf = static_cast<F *>(at(o_pdf));
        out.eta = static_cast<F *>(at(o_eta));
        out.flags = static_cast<uint8_t *>(at(o_fl));
        out.valid = static_cast<bool *>(at(o_va));
        out.proportional = static_cast<bool *>(at(o_pr));
        arrays = py::make_tuple(wi, f, pdf, fl, eta, va, pr);
    }
};

// One bound model (core/bxdf.h): both precisions, built from one Params (kept for `params`).
template <template <typename> class Model> struct PyModel {
    Model<float> m32;
    Model<double> m64;
    typename Model<double>::Params params;
    // Per-element parameters (bind_varying.h), in field order; empty for a uniform model, whose
    // calls take the paths below unchanged.
    std::vector<VaryingField> varying;
    mutable int flags_union = -1;  // varying: the union of the elements' flags, computed on first use

    // The lobes: the model's, or with per-element parameters the union over the elements'.
    uint8_t flags() const {
        if (varying.empty()) return m64.flags();
        if (flags_union < 0) {
            // over the planes' own broadcast (every joint element: smoothness may depend on two)
            std::vector<py::array> keep;
            const door::Shape shape = broadcast_with({}, {}, varying);
            std::vector<ParamPlane> pl = planes_for(varying, shape, keep);
            VaryingParams<typename Model<double>::Params> vp{params, pl.data(), int(pl.size())};
            const int64_t n = door::prod(shape);
            int u = 0;
            py::gil_scoped_release release;
            for (int64_t i = 0; i < n; ++i)
                if (i == 0 || !vp.same(i - 1, i)) u |= Model<double>::make(vp.at(i)).flags();
            flags_union = u;
        }
        return uint8_t(flags_union);
    }

    // albedo's n_samples: 2**40 samples per direction run for hours already (Python's twin:
    // _arrays.MAX_ALBEDO_SAMPLES).
    static constexpr long long kMaxAlbedoSamples = 1LL << 40;

    template <typename F> const Model<F> &get() const {
        if constexpr (std::is_same_v<F, float>) return m32; else return m64;
    }


    // ---- fast entry points: the whole call on plain arguments (see Plain), None otherwise ----
    // eval_fast / pdf_fast on plain arguments: allocates or accepts the output, runs the kernel
    // without the GIL, raises on bad directions. Direction or output planes (Fortran-order (N, 3)
    // arrays) go to the packet kernels' run-time layout path (batch.h eval_batch_dirs), which
    // gives bit-identical values; a model without packets leaves them to the general path (None).
    // eval's result is Fortran-ordered when every full-length direction argument is (numpy's
    // order='K' rule), else C-ordered.
    template <typename F, bool Eval>
    py::object pair_plain(const Plain &o, const Plain &i, const Plain &big, TransportMode md, uint8_t sf,
                          py::handle out) const {
        constexpr bool packets = is_vectorized<Model<F>>::value;
        int64_t n = big.rows;
        std::vector<py::ssize_t> shape = batch_shape(big, 1, Eval ? std::initializer_list<py::ssize_t>{3}
                                                                   : std::initializer_list<py::ssize_t>{});
        bool any_planes = o.planes || i.planes, out_planes = false;
        if (!packets && any_planes) return py::none();
        py::array res;
        if (out.is_none()) {
            out_planes = Eval && any_planes && (o.rows != n || o.planes) && (i.rows != n || i.planes) && n > 1;
            if (out_planes) res = py::array_t<F, py::array::f_style>(shape);
            else res = result_array<F>(shape);
        } else if (plain_out(out, o.type, shape, Eval && packets ? &out_planes : nullptr)) {
            res = py::reinterpret_borrow<py::array>(out);
            check_out_no_overlap(res, py::reinterpret_borrow<py::array>(o.obj), py::reinterpret_borrow<py::array>(i.obj));
        } else {
            return py::none();
        }
        if (n == 0) return std::move(res);
        const F *po = static_cast<const F *>(o.data), *pi = static_cast<const F *>(i.data);
        F *pout = static_cast<F *>(res.mutable_data());
        BadCounts bad;
        {
            py::gil_scoped_release release;
            const Model<F> &m = get<F>();
            int nt = num_threads();
            auto run = [&](auto so, auto si) {
                constexpr int SO = decltype(so)::value, SI = decltype(si)::value;
                if constexpr (Eval) eval_batch<SO, SI>(m, po, pi, n, md, pout, nt, bad);
                else pdf_batch<SO, SI>(m, po, pi, n, md, sf, pout, nt, bad);
            };
            using Full = std::integral_constant<int, 3>;
            using One = std::integral_constant<int, 0>;
            bool done = false;
            if constexpr (packets) {
                if (any_planes || out_planes) {
                    Dirs<F> dwo = dirs_of_plain<F>(o, n), dwi = dirs_of_plain<F>(i, n);
                    if constexpr (Eval) eval_batch_dirs(m, dwo, dwi, n, md, pout, out_planes ? n : 0, nt, bad);
                    else pdf_batch_dirs(m, dwo, dwi, n, md, sf, pout, nt, bad);
                    done = true;
                }
            }
            if (done) {
            } else if (o.rows == n && i.rows == n) run(Full{}, Full{});
            else if (o.rows == n) run(Full{}, One{});
            else if (i.rows == n) run(One{}, Full{});
            else run(One{}, One{});
        }
        raise_if_interrupted();
        raise_bad(bad, true, false);
        return std::move(res);
    }


    // sample's out=: the seven arrays of a SampleResult (its fields, SampleResult order), each of
    // this call's shape, dtype and C order and writeable, as the kernel's outputs, held in keep for
    // the call; false when any is not (the door has worded the error before: check_sample_out).
    // res may also be a tuple of the seven arrays (the benchmarks' preallocated outputs).
    template <typename F>
    static bool sample_out_of(py::handle res, const std::vector<py::ssize_t> &batch, SampleOut<F> &o,
                              py::object (&keep)[7]) {
        using api = py::detail::npy_api;
        const int t = py::dtype::of<F>().num();
        std::vector<py::ssize_t> b3(batch);
        b3.push_back(3);
        void *p[7];
        const int types[7] = {t, t, t, api::NPY_UBYTE_, t, api::NPY_BOOL_, api::NPY_BOOL_};
        for (int k = 0; k < 7; ++k) {
            keep[k] = sample_out_field(res, k);  // alive for the call, whatever res's fields become
            PyObject *a = keep[k].ptr();
            p[k] = plain_out_data(a, types[k], k < 2 ? b3 : batch);
            if (!p[k]) return false;
        }
        o.wi = static_cast<F *>(p[0]);
        o.f = static_cast<F *>(p[1]);
        o.pdf = static_cast<F *>(p[2]);
        o.flags = static_cast<uint8_t *>(p[3]);
        o.eta = static_cast<F *>(p[4]);
        o.valid = static_cast<bool *>(p[5]);
        o.proportional = static_cast<bool *>(p[6]);
        return true;
    }


    // The outputs in a new SampleBlock (res None: returns its arrays) or in res's arrays (returns
    // res; None when they do not fit: sample_out_of).
    template <typename F>
    py::object sample_plain(const Plain &o, const Plain &c, const Plain &u, TransportMode md, uint8_t sf,
                            py::handle res) const {
        int64_t n = c.rows;
        std::vector<py::ssize_t> batch = batch_shape(c, 0, {});
        std::optional<SampleBlock<F>> blk;
        SampleOut<F> out;
        py::object keep[7];
        if (res.is_none()) {
            blk.emplace(batch, n);
            out = blk->out;
        } else if (!sample_out_of<F>(res, batch, out, keep)) {
            return py::none();
        } else {
            // the kernel's pointers are restrict (batch.h): the same check as the general path
            // (an out= whose pdf array was also its eta array came back with wrong values before)
            auto arr = [](PyObject *a) { return py::reinterpret_borrow<py::array>(a); };
            py::array a[10] = {arr(o.obj), arr(c.obj), arr(u.obj), arr(keep[0].ptr()), arr(keep[1].ptr()),
                               arr(keep[2].ptr()), arr(keep[3].ptr()), arr(keep[4].ptr()), arr(keep[5].ptr()),
                               arr(keep[6].ptr())};
            check_sample_no_overlap({&a[0], &a[1], &a[2], &a[3], &a[4], &a[5], &a[6], &a[7], &a[8], &a[9]}, 3);
        }
        py::object ret = blk ? py::object(blk->arrays) : py::reinterpret_borrow<py::object>(res);
        if (n == 0) return ret;
        const F *po = static_cast<const F *>(o.data), *pc = static_cast<const F *>(c.data),
                *pu = static_cast<const F *>(u.data);
        // Fortran-order wo / u (planes, e.g. the .T of a (3, N) array): the sample kernels read rows,
        // so the planes are transposed into scratch rows first, on the pool's threads (the general
        // path's numpy conversion took ~6 ms per (1e6, 3) float32 array, 3.5x the kernel). The
        // scratch is a result_array: from 1 MiB on a block-cache block, whose pages stay warm.
        const py::ssize_t scratch = py::ssize_t(o.planes ? 3 * n : 0) + py::ssize_t(u.planes ? 2 * n : 0);
        py::array scratch_rows = result_array<F>({scratch});
        F *rows = static_cast<F *>(scratch_rows.mutable_data());
        F *rows_o = o.planes ? rows : nullptr, *rows_u = u.planes ? rows + (o.planes ? 3 * n : 0) : nullptr;
        BadCounts bad;
        {
            py::gil_scoped_release release;
            const Model<F> &m = get<F>();
            // an interrupted transposition leaves the scratch incomplete: no kernel on it (the
            // interrupt raises below)
            bool ready = !rows_o || planes_to_rows<3>(po, n, rows_o, num_threads());
            ready = ready && (!rows_u || planes_to_rows<2>(pu, n, rows_u, num_threads()));
            if (rows_o) po = rows_o;
            if (rows_u) pu = rows_u;
            if (ready && o.rows == n) sample_batch<3>(m, po, pc, pu, n, md, sf, out, num_threads(), bad);
            else if (ready) sample_batch<0>(m, po, pc, pu, n, md, sf, out, num_threads(), bad);
        }
        raise_if_interrupted();
        raise_bad(bad, false, true);
        return ret;
    }

    template <typename F> py::object albedo_plain(const Plain &o, int64_t n_samples, uint64_t seed, TransportMode md) const {
        py::array_t<F> res(batch_shape(o, 1, {3}));
        if (o.rows == 0) return std::move(res);
        BadCounts bad;
        {
            py::gil_scoped_release release;
            albedo_batch(get<F>(), static_cast<const F *>(o.data), o.rows, n_samples, seed, md, res.mutable_data(),
                         num_threads(), bad);
        }
        raise_if_interrupted();
        raise_bad(bad, false, false);
        return std::move(res);
    }

    // ---- per-element parameters (bind_varying.h, batch_varying.h): the door of a model with
    // varying fields. Every argument and plane is broadcast to the call's batch (numpy rules over
    // the directions', uniforms' and parameters' shapes) as full C-order rows, then the varying
    // kernels run. out= is written by copy.
    using VParams = VaryingParams<typename Model<double>::Params>;

    static py::array full_rows(const py::array &a, const door::Shape &batch, size_t tail, int type) {
        return door::rows(a, batch, tail, type, true);
    }

    static void copy_into(py::handle target, py::handle src) {
        if (py::detail::npy_api::get().PyArray_CopyInto_(target.ptr(), src.ptr()) != 0) throw py::error_already_set();
    }

    py::object varying_pair(bool eval, py::handle wo, py::handle wi, py::handle mode, py::handle sflags,
                            py::handle out) const {
        using door::Shape;
        const int md = door::mode_arg(mode), sf = eval ? 0 : door::sflags_arg(sflags);
        py::array a = door::dirs(wo, "wo"), b = door::dirs(wi, "wi");
        const int type = door::is_f32(a) && door::is_f32(b) ? py::detail::npy_api::NPY_FLOAT_
                                                            : py::detail::npy_api::NPY_DOUBLE_;
        const Shape batch = broadcast_with({"wo", "wi"}, {door::lead(door::shape_of(a), 1),
                                                          door::lead(door::shape_of(b), 1)}, varying);
        const Shape shape = eval ? door::cat(batch, {3}) : batch;
        if (!out.is_none()) door::check_out(out, shape, type, false);
        a = full_rows(a, batch, 1, type);
        b = full_rows(b, batch, 1, type);
        std::vector<py::array> keep;
        std::vector<ParamPlane> pl = planes_for(varying, batch, keep);
        const VParams vp{params, pl.data(), int(pl.size())};
        const int64_t n = door::prod(batch);
        py::array res = type == py::detail::npy_api::NPY_FLOAT_ ? py::array(py::array_t<float>(shape))
                                                                : py::array(py::array_t<double>(shape));
        BadCounts bad;
        if (n > 0) {
            py::gil_scoped_release release;
            auto run = [&](auto tag) {
                using F = decltype(tag);
                const F *po = static_cast<const F *>(a.data()), *pi = static_cast<const F *>(b.data());
                F *po_ = static_cast<F *>(res.mutable_data());
                if (eval) varying_pair_batch<true, Model<F>>(vp, po, pi, n, TransportMode(md), 0, po_, num_threads(), bad);
                else varying_pair_batch<false, Model<F>>(vp, po, pi, n, TransportMode(md), uint8_t(sf), po_, num_threads(), bad);
            };
            if (type == py::detail::npy_api::NPY_FLOAT_) run(float{});
            else run(double{});
        }
        raise_if_interrupted();
        raise_bad(bad, true, false);
        if (out.is_none()) return std::move(res);
        copy_into(out, res);
        return py::reinterpret_borrow<py::object>(out);
    }

    py::object varying_sample(py::handle wo, py::handle uc, py::handle u, py::handle mode, py::handle sflags,
                              py::handle out, py::handle n_arg, py::handle seed) const {
        using door::Shape;
        const int md = door::mode_arg(mode), sf = door::sflags_arg(sflags);
        py::array a = door::dirs(wo, "wo"), c, w;
        Shape batch;
        int type;
        if (!n_arg.is_none()) {
            if (!uc.is_none() || !u.is_none()) door::value_error("n: give either n (and seed) or the uniforms uc and u, not both");
            const long long nn = door::int_arg(n_arg, "n", 0);
            batch = broadcast_with({"wo", "n"}, {door::lead(door::shape_of(a), 1), Shape{py::ssize_t(nn)}}, varying);
            type = door::is_f32(a) ? py::detail::npy_api::NPY_FLOAT_ : py::detail::npy_api::NPY_DOUBLE_;
            const uint64_t sd = door::seed_arg(seed);
            c = py::array(py::dtype(type), batch);
            w = py::array(py::dtype(type), door::cat(batch, {2}));
            {
                py::gil_scoped_release release;
                if (type == py::detail::npy_api::NPY_FLOAT_)
                    fill_uniforms<float>(sd, static_cast<float *>(c.mutable_data()), static_cast<float *>(w.mutable_data()), c.size());
                else
                    fill_uniforms<double>(sd, static_cast<double *>(c.mutable_data()), static_cast<double *>(w.mutable_data()), c.size());
            }
            raise_if_interrupted();
        } else {
            if (uc.is_none() || u.is_none()) door::value_error("uc, u: pass both uniforms, or n= and seed=");
            c = door::uniforms(uc, "uc", false);
            w = door::uniforms(u, "u", true);
            const bool uc_weak = PyFloat_CheckExact(uc.ptr()) || (PyLong_CheckExact(uc.ptr()));
            type = door::is_f32(a) && (uc_weak || door::is_f32(c)) && door::is_f32(w) ? py::detail::npy_api::NPY_FLOAT_
                                                                                     : py::detail::npy_api::NPY_DOUBLE_;
            batch = broadcast_with({"wo", "uc", "u"}, {door::lead(door::shape_of(a), 1), door::shape_of(c),
                                                       door::lead(door::shape_of(w), 1)}, varying);
            c = full_rows(c, batch, 0, type);
            w = full_rows(w, batch, 1, type);
        }
        if (!out.is_none()) check_sample_out(out, batch, type);
        a = full_rows(a, batch, 1, type);
        std::vector<py::array> keep;
        std::vector<ParamPlane> pl = planes_for(varying, batch, keep);
        const VParams vp{params, pl.data(), int(pl.size())};
        const int64_t n = door::prod(batch);
        py::object ret;
        BadCounts bad;
        auto run = [&](auto tag) {
            using F = decltype(tag);
            SampleBlock<F> blk(batch, n);
            ret = blk.arrays;
            if (n == 0) return;
            py::gil_scoped_release release;
            varying_sample_batch<Model<F>>(vp, static_cast<const F *>(a.data()), static_cast<const F *>(c.data()),
                                           static_cast<const F *>(w.data()), n, TransportMode(md), uint8_t(sf), blk.out,
                                           num_threads(), bad);
        };
        if (type == py::detail::npy_api::NPY_FLOAT_) run(float{});
        else run(double{});
        raise_if_interrupted();
        raise_bad(bad, false, true);
        if (out.is_none()) return ret;
        py::tuple t = ret;
        for (int k = 0; k < 7; ++k) copy_into(sample_out_field(out, k), t[k]);
        return py::reinterpret_borrow<py::object>(out);
    }

    py::object varying_albedo(py::handle wo, py::handle n_samples, py::handle seed, py::handle mode) const {
        const int md = door::mode_arg(mode);
        py::array a = door::dirs(wo, "wo");
        const long long ns = door::int_arg(n_samples, "n_samples", 1, kMaxAlbedoSamples);
        if (seed.is_none()) door::type_error("seed: expected an integer, got NoneType");
        const uint64_t sd = door::seed_arg(seed);
        const int type = door::is_f32(a) ? py::detail::npy_api::NPY_FLOAT_ : py::detail::npy_api::NPY_DOUBLE_;
        const door::Shape batch = broadcast_with({"wo"}, {door::lead(door::shape_of(a), 1)}, varying);
        a = full_rows(a, batch, 1, type);
        std::vector<py::array> keep;
        std::vector<ParamPlane> pl = planes_for(varying, batch, keep);
        const VParams vp{params, pl.data(), int(pl.size())};
        const int64_t n = door::prod(batch);
        py::array res = type == py::detail::npy_api::NPY_FLOAT_ ? py::array(py::array_t<float>(door::cat(batch, {3})))
                                                                : py::array(py::array_t<double>(door::cat(batch, {3})));
        BadCounts bad;
        if (n > 0) {
            py::gil_scoped_release release;
            auto run = [&](auto tag) {
                using F = decltype(tag);
                varying_albedo_batch<Model<F>>(vp, static_cast<const F *>(a.data()), n, ns, sd, TransportMode(md),
                                               static_cast<F *>(res.mutable_data()), num_threads(), bad);
            };
            if (type == py::detail::npy_api::NPY_FLOAT_) run(float{});
            else run(double{});
        }
        raise_if_interrupted();
        raise_bad(bad, false, false);
        return std::move(res);
    }

    // ---- the door: one entry per operation (see the top of this file) ----
    // The plain arguments take the fast path above; anything else is converted and checked here
    // (door.h), in the same call, and then runs the same kernels.

    template <bool Eval>
    py::object pair_door(py::handle wo, py::handle wi, py::handle mode, py::handle sflags, py::handle out) const {
        if (!varying.empty()) return varying_pair(Eval, wo, wi, mode, sflags, out);
        {
            Plain o, i;
            const Plain *big;
            int md = small_int(mode, 0, 1), sf = Eval ? 0 : small_int(sflags, 0, 3);
            if (md >= 0 && sf >= 0 && plain(wo, 1, 3, o, true) && plain(wi, 1, 3, i, true) && o.type == i.type &&
                simple_batch(o, 1, i, 1, big)) {
                py::object r = o.type == py::detail::npy_api::NPY_FLOAT_
                                   ? pair_plain<float, Eval>(o, i, *big, TransportMode(md), uint8_t(sf), out)
                                   : pair_plain<double, Eval>(o, i, *big, TransportMode(md), uint8_t(sf), out);
                if (!r.is_none()) return r;
            }
        }
        using door::Shape;
        const int md = door::mode_arg(mode), sf = Eval ? 0 : door::sflags_arg(sflags);
        py::array a = door::dirs(wo, "wo"), b = door::dirs(wi, "wi");
        const int type = door::is_f32(a) && door::is_f32(b) ? py::detail::npy_api::NPY_FLOAT_
                                                            : py::detail::npy_api::NPY_DOUBLE_;
        const Shape batch = door::broadcast({"wo", "wi"}, {door::lead(door::shape_of(a), 1), door::lead(door::shape_of(b), 1)});
        const Shape shape = Eval ? door::cat(batch, {3}) : batch;
        // eval's result order (numpy's order='K'): Fortran when the batch is 1-D of more than one
        // element and every direction array of the whole batch is Fortran-ordered (N, 3) planes.
        bool f_order = false;
        if (Eval && batch.size() == 1 && batch[0] > 1) {
            bool any = false, all = true;
            for (const py::array *x : {&a, &b})
                if (door::lead(door::shape_of(*x), 1) == batch) {
                    any = true;
                    all = all && (x->flags() & py::array::f_style) && !(x->flags() & py::array::c_style);
                }
            f_order = any && all;
        }
        py::object target = py::reinterpret_borrow<py::object>(out);
        if (!out.is_none()) door::check_out(out, shape, type, Eval && batch.size() == 1);
        else if (f_order) target = py::array(py::dtype(type), shape, std::vector<py::ssize_t>{py::ssize_t(py::dtype(type).itemsize()),
                                                                                         py::ssize_t(py::dtype(type).itemsize()) * batch[0]});
        a = door::rows(a, batch, 1, type);
        b = door::rows(b, batch, 1, type);
        if (door::prod(door::lead(door::shape_of(a), 1)) == door::prod(batch)) door::shape_batch(a, batch, 1);
        else door::shape_batch(b, batch, 1);
        Plain o, i;
        const Plain *big = nullptr;
        if (!plain(a, 1, 3, o) || !plain(b, 1, 3, i) || !simple_batch(o, 1, i, 1, big))
            throw std::logic_error("bsdfkit: the door's converted arguments are not plain");  // cannot happen
        auto run = [&](py::handle res) {
            return type == py::detail::npy_api::NPY_FLOAT_
                       ? pair_plain<float, Eval>(o, i, *big, TransportMode(md), uint8_t(sf), res)
                       : pair_plain<double, Eval>(o, i, *big, TransportMode(md), uint8_t(sf), res);
        };
        if (target.is_none()) return run(py::none());
        py::object r = run(target);
        if (!r.is_none()) return r;
        // an out= the kernels cannot write directly (Fortran-order planes of a model without
        // packets): computed in C order, then copied
        py::object tmp = run(py::none());
        if (py::detail::npy_api::get().PyArray_CopyInto_(target.ptr(), tmp.ptr()) != 0) throw py::error_already_set();
        return target;
    }

    py::object eval(py::handle wo, py::handle wi, py::handle mode, py::handle out) const {
        return pair_door<true>(wo, wi, mode, py::none(), out);
    }
    py::object pdf(py::handle wo, py::handle wi, py::handle mode, py::handle sflags, py::handle out) const {
        return pair_door<false>(wo, wi, mode, sflags, out);
    }

    // One of sample's out= arrays (k in SampleResult order): the attribute of a SampleResult, or
    // the k-th item of a tuple of seven arrays.
    static py::object sample_out_field(py::handle res, int k) {
        static const char *const names[7] = {"wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional"};
        if (PyTuple_Check(res.ptr()) && PyTuple_GET_SIZE(res.ptr()) == 7)
            return py::reinterpret_borrow<py::object>(PyTuple_GET_ITEM(res.ptr(), k));
        PyObject *a = PyObject_GetAttrString(res.ptr(), names[k]);
        if (!a) {
            PyErr_Clear();
            door::type_error("out: expected a SampleResult (e.g. an earlier result of sample), got " + door::type_name(res));
        }
        return py::reinterpret_steal<py::object>(a);
    }

    // sample's out= in numpy's words, each array named (out.wi, out.f, ...).
    static void check_sample_out(py::handle res, const door::Shape &batch, int type) {
        using api = py::detail::npy_api;
        static const char *const names[7] = {"out.wi", "out.f", "out.pdf", "out.flags", "out.eta", "out.valid",
                                             "out.pdf_is_proportional"};
        const int types[7] = {type, type, type, api::NPY_UBYTE_, type, api::NPY_BOOL_, api::NPY_BOOL_};
        for (int k = 0; k < 7; ++k)
            door::check_out(sample_out_field(res, k), k < 2 ? door::cat(batch, {3}) : batch, types[k], false, names[k]);
    }

    // Seeded uniforms: uc, u of element i from a counter hash of (seed, i), as albedo's (batch.h):
    // the same values for any thread count, chunking or array position.
    template <typename F> static void fill_uniforms(uint64_t seed, F *uc, F *u, int64_t n) {
        parallel_chunks(n, num_threads(), int64_t(1) << 15, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) {
                uint64_t h = hash3(seed, uint64_t(i), 0x5a3d1e);
                uc[i] = uniform_from_bits<F>(mix64(h ^ 1));
                u[2 * i] = uniform_from_bits<F>(mix64(h ^ 2));
                u[2 * i + 1] = uniform_from_bits<F>(mix64(h ^ 3));
            }
        });
    }

    // uc of the batch shape, u of the batch shape + (2,), wo of the batch shape + (3,) or one
    // direction (plain), or anything numpy broadcasts to that, or n (and seed) instead of uc, u.
    // Returns the SampleResult fields (wi, f, pdf, flags, eta, valid, pdf_is_proportional), or,
    // given out (a SampleResult of this call's shapes and dtypes), out after writing into it.
    py::object sample(py::handle wo, py::handle uc, py::handle u, py::handle mode, py::handle sflags, py::handle out,
                      py::handle n, py::handle seed) const {
        if (!varying.empty()) return varying_sample(wo, uc, u, mode, sflags, out, n, seed);
        if (n.is_none()) {
            Plain o, c, w;
            const Plain *big;
            int md = small_int(mode, 0, 1), sf = small_int(sflags, 0, 3);
            if (md >= 0 && sf >= 0 && plain(wo, 1, 3, o, true) && plain(uc, 0, 0, c) && plain(u, 1, 2, w, true) &&
                c.type == o.type && w.type == o.type && w.ndim == c.ndim + 1 &&
                std::equal(c.shape, c.shape + c.ndim, w.shape) && simple_batch(c, 0, o, 1, big) && big == &c) {
                py::object r = o.type == py::detail::npy_api::NPY_FLOAT_
                                   ? sample_plain<float>(o, c, w, TransportMode(md), uint8_t(sf), out)
                                   : sample_plain<double>(o, c, w, TransportMode(md), uint8_t(sf), out);
                if (!r.is_none()) return r;
            }
        }
        using door::Shape;
        const int md = door::mode_arg(mode), sf = door::sflags_arg(sflags);
        py::array a = door::dirs(wo, "wo"), c, w;
        Shape batch;
        int type;
        if (!n.is_none()) {
            if (!uc.is_none() || !u.is_none()) door::value_error("n: give either n (and seed) or the uniforms uc and u, not both");
            const long long nn = door::int_arg(n, "n", 0);
            batch = door::broadcast({"wo", "n"}, {door::lead(door::shape_of(a), 1), Shape{py::ssize_t(nn)}});
            type = door::is_f32(a) ? py::detail::npy_api::NPY_FLOAT_ : py::detail::npy_api::NPY_DOUBLE_;
            const uint64_t sd = door::seed_arg(seed);
            c = py::array(py::dtype(type), batch);
            w = py::array(py::dtype(type), door::cat(batch, {2}));
            {
                py::gil_scoped_release release;
                if (type == py::detail::npy_api::NPY_FLOAT_)
                    fill_uniforms<float>(sd, static_cast<float *>(c.mutable_data()), static_cast<float *>(w.mutable_data()), c.size());
                else
                    fill_uniforms<double>(sd, static_cast<double *>(c.mutable_data()), static_cast<double *>(w.mutable_data()), c.size());
            }
            raise_if_interrupted();
        } else {
            if (uc.is_none() || u.is_none()) door::value_error("uc, u: pass both uniforms, or n= and seed=");
            c = door::uniforms(uc, "uc", false);
            w = door::uniforms(u, "u", true);
            // a Python float (or int) uc is weak, as numpy's scalars (NEP 50): m.sample(wo32, 0.5, u32)
            // runs the float32 kernels
            const bool uc_weak = PyFloat_CheckExact(uc.ptr()) || (PyLong_CheckExact(uc.ptr()));
            type = door::is_f32(a) && (uc_weak || door::is_f32(c)) && door::is_f32(w) ? py::detail::npy_api::NPY_FLOAT_
                                                                                     : py::detail::npy_api::NPY_DOUBLE_;
            batch = door::broadcast({"wo", "uc", "u"}, {door::lead(door::shape_of(a), 1), door::shape_of(c),
                                                        door::lead(door::shape_of(w), 1)});
            c = door::rows(c, batch, 0, type, true);
            w = door::rows(w, batch, 1, type, true);
        }
        if (!out.is_none()) check_sample_out(out, batch, type);
        a = door::rows(a, batch, 1, type);
        Plain o, pc, pw;
        if (!plain(a, 1, 3, o) || !plain(c, 0, 0, pc) || !plain(w, 1, 2, pw))
            throw std::logic_error("bsdfkit: the door's converted arguments are not plain");  // cannot happen
        py::object r = type == py::detail::npy_api::NPY_FLOAT_ ? sample_plain<float>(o, pc, pw, TransportMode(md), uint8_t(sf), out)
                                                               : sample_plain<double>(o, pc, pw, TransportMode(md), uint8_t(sf), out);
        if (r.is_none()) door::value_error("out: its arrays must be this call's outputs (see SampleResult)");
        return r;
    }

    py::object albedo(py::handle wo, py::handle n_samples, py::handle seed, py::handle mode) const {
        if (!varying.empty()) return varying_albedo(wo, n_samples, seed, mode);
        {
            Plain o;
            int md = small_int(mode, 0, 1);
            if (md >= 0 && plain(wo, 1, 3, o) && PyLong_CheckExact(n_samples.ptr()) && PyLong_CheckExact(seed.ptr())) {
                long long ns = PyLong_AsLongLong(n_samples.ptr()), sd = PyLong_AsLongLong(seed.ptr());
                if (PyErr_Occurred()) PyErr_Clear();
                else if (ns >= 1 && ns <= kMaxAlbedoSamples && sd >= 0)
                    return o.type == py::detail::npy_api::NPY_FLOAT_
                               ? albedo_plain<float>(o, ns, uint64_t(sd), TransportMode(md))
                               : albedo_plain<double>(o, ns, uint64_t(sd), TransportMode(md));
            }
        }
        const int md = door::mode_arg(mode);
        py::array a = door::dirs(wo, "wo");
        const long long ns = door::int_arg(n_samples, "n_samples", 1, kMaxAlbedoSamples);
        if (seed.is_none()) door::type_error("seed: expected an integer, got NoneType");
        const uint64_t sd = door::seed_arg(seed);
        const int type = door::is_f32(a) ? py::detail::npy_api::NPY_FLOAT_ : py::detail::npy_api::NPY_DOUBLE_;
        a = door::rows(a, door::lead(door::shape_of(a), 1), 1, type);
        Plain o;
        if (!plain(a, 1, 3, o)) throw std::logic_error("bsdfkit: the door's converted arguments are not plain");
        return type == py::detail::npy_api::NPY_FLOAT_ ? albedo_plain<float>(o, ns, sd, TransportMode(md))
                                                       : albedo_plain<double>(o, ns, sd, TransportMode(md));
    }
};

template <template <typename> class Model>
py::class_<PyModel<Model>> bind_model(py::module_ &m, const char *name) {
    using P = PyModel<Model>;
    py::class_<P> c(m, name);
    c.def("eval", &P::eval, py::arg("wo"), py::arg("wi"), py::arg("mode") = 0, py::arg("out") = py::none())
        .def("pdf", &P::pdf, py::arg("wo"), py::arg("wi"), py::arg("mode") = 0, py::arg("sflags") = 3,
             py::arg("out") = py::none())
        .def("sample", &P::sample, py::arg("wo"), py::arg("uc") = py::none(), py::arg("u") = py::none(),
             py::arg("mode") = 0, py::arg("sflags") = 3, py::arg("out") = py::none(), py::arg("n") = py::none(),
             py::arg("seed") = py::none())
        .def("albedo", &P::albedo, py::arg("wo"), py::arg("n_samples") = 65536, py::arg("seed") = 0, py::arg("mode") = 0)
        .def_property_readonly("flags", [](const P &self) { return int(self.flags()); });
    return c;
}

} // namespace bsdfkit::py_bind
