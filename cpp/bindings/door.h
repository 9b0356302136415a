// The general half of the one door per operation (bind_model.h PyModel::eval / pdf / sample /
// albedo): arguments that are not plain (Python scalars and lists, other real dtypes,
// non-contiguous or broadcasting arrays) are converted here with numpy's C API, in the same call
// that runs the kernel, and every argument error is worded here, once, naming the argument.
// Nothing in this file is per model (compiled once per translation unit, inline).
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace bsdfkit::py_bind::door {

namespace py = pybind11;
using Shape = std::vector<py::ssize_t>;

[[noreturn]] inline void type_error(const std::string &msg) { throw py::type_error(msg); }
[[noreturn]] inline void value_error(const std::string &msg) { throw py::value_error(msg); }

inline std::string repr_of(py::handle h) { return py::repr(h); }
inline py::tuple to_tuple(const Shape &s) {
    py::tuple t(s.size());
    for (size_t k = 0; k < s.size(); ++k) t[k] = py::int_(s[k]);
    return t;
}
inline std::string shape_repr(const Shape &s) { return repr_of(to_tuple(s)); }
inline std::string type_name(py::handle h) { return py::str(py::type::of(h).attr("__name__")); }

inline auto &api() { return py::detail::npy_api::get(); }
inline bool is_ndarray(py::handle h) { return Py_TYPE(h.ptr()) == api().PyArray_Type_ || PyObject_TypeCheck(h.ptr(), api().PyArray_Type_); }

inline Shape shape_of(const py::array &a) { return Shape(a.shape(), a.shape() + a.ndim()); }
inline Shape lead(const Shape &s, size_t tail) { return Shape(s.begin(), s.end() - py::ssize_t(tail)); }
inline py::ssize_t prod(const Shape &s) {
    py::ssize_t p = 1;
    for (auto v : s) p *= v;
    return p;
}
inline Shape cat(Shape s, std::initializer_list<py::ssize_t> tail) {
    s.insert(s.end(), tail);
    return s;
}

// x as a numpy array of a real (float / int / uint) dtype, or TypeError naming it (as numpy.asarray).
inline py::array real_array(py::handle x, const char *name) {
    PyObject *a = api().PyArray_FromAny_(x.ptr(), nullptr, 0, 0, 0, nullptr);
    if (!a) {
        py::error_already_set e;
        type_error(std::string(name) + ": cannot be converted to a numeric array (" + e.what() + ")");
    }
    py::array arr = py::reinterpret_steal<py::array>(a);
    char kind = arr.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        type_error(std::string(name) + ": expected a real numeric array, got dtype " + std::string(py::str(arr.dtype())));
    return arr;
}

// An array of directions: last axis 3, float16 refused (its 11-bit significand cannot hold a unit vector).
inline py::array dirs(py::handle x, const char *name) {
    py::array a = real_array(x, name);
    if (a.dtype().kind() == 'f' && a.dtype().itemsize() == 2)
        type_error(std::string(name) + ": float16 is not supported (its 11-bit significand cannot hold a unit vector to "
                   "the 1e-4 the kernels require); pass float32 (e.g. .astype(np.float32)) or float64");
    if (a.ndim() == 0 || a.shape(a.ndim() - 1) != 3)
        value_error(std::string(name) + ": expected an array of directions with last axis of length 3, got shape " +
                    shape_repr(shape_of(a)));
    return a;
}

// Uniforms with trailing shape (2,) (u) or () (uc); their values are counted by the kernel.
inline py::array uniforms(py::handle x, const char *name, bool pair) {
    py::array a = real_array(x, name);
    if (pair && (a.ndim() == 0 || a.shape(a.ndim() - 1) != 2))
        value_error(std::string(name) + ": expected trailing shape (2,), got " + shape_repr(shape_of(a)));
    return a;
}

inline bool is_f32(const py::array &a) { return a.dtype().kind() == 'f' && a.dtype().itemsize() == 4; }

// numpy's broadcasting of batch shapes, or ValueError naming the arguments.
inline Shape broadcast(std::initializer_list<const char *> names, std::initializer_list<Shape> shapes) {
    size_t nd = 0;
    for (auto &s : shapes) nd = std::max(nd, s.size());
    Shape r(nd, 1);
    bool ok = true;
    for (auto &s : shapes)
        for (size_t k = 0; k < s.size(); ++k) {
            py::ssize_t &d = r[nd - s.size() + k];
            py::ssize_t v = s[k];
            if (d == 1) d = v;
            else if (v != 1 && v != d) ok = false;
        }
    if (!ok) {
        std::string joined, desc;
        auto n = names.begin();
        for (auto &s : shapes) {
            joined += (joined.empty() ? "" : " and ") + std::string(*n);
            desc += (desc.empty() ? "" : ", ") + std::string(*n) + " " + shape_repr(s);
            ++n;
        }
        value_error(joined + ": batch shapes cannot be broadcast together (" + desc + ")");
    }
    return r;
}

// a as C-contiguous native `type` rows for a call over `batch`: its own shape when its batch is
// the whole batch or a single item (the kernels' "one" argument), else broadcast to batch + tail
// (a copy). full: always the whole batch (sample's uniforms).
inline py::array rows(const py::array &a, const Shape &batch, size_t tail, int type, bool full = false) {
    const Shape sa = shape_of(a), b = lead(sa, tail);
    py::object src = a;
    if (b != batch && (full || prod(b) != 1)) {
        Shape target = batch;
        target.insert(target.end(), sa.end() - py::ssize_t(tail), sa.end());
        src = py::module_::import("numpy").attr("broadcast_to")(a, to_tuple(target));
    }
    // NPY_ARRAY_C_CONTIGUOUS | ALIGNED | NOTSWAPPED | FORCECAST (a float64 value into the float32
    // kernels when the call is float32, as numpy.ascontiguousarray(dtype=) casts)
    constexpr int req = 0x0001 | 0x0100 | 0x0200 | 0x0010;
    PyObject *descr = api().PyArray_DescrFromType_(type);
    PyObject *r = api().PyArray_FromAny_(src.ptr(), descr, 0, 0, req, nullptr);  // steals descr
    if (!r) throw py::error_already_set();
    return py::reinterpret_steal<py::array>(r);
}

// Reshapes the first of `args` whose row count is the batch's to exactly batch + tail (a view),
// so the kernels' entry sees the batch shape on one argument (a single-item batch, e.g. wo (3,)
// against wi (1, 1, 3), or (5,) against (1, 1, 3)'s broadcast (1, 5)).
inline void shape_batch(py::array &a, const Shape &batch, size_t tail) {
    const Shape s = shape_of(a);
    Shape want = batch;
    want.insert(want.end(), s.end() - py::ssize_t(tail), s.end());
    if (s != want) a = a.reshape(want);
}

// mode: a TransportMode (or its int 0 / 1, or its name in any case).
inline int mode_arg(py::handle mode) {
    PyObject *o = mode.ptr();
    if (PyLong_Check(o)) {
        long v = PyLong_AsLong(o);
        if (v == 0 || v == 1) return int(v);
        PyErr_Clear();
    } else if (PyUnicode_Check(o)) {
        std::string s = py::str(mode);
        for (auto &c : s) c = char(std::tolower(c));
        if (s == "radiance") return 0;
        if (s == "importance") return 1;
    }
    value_error("mode: must be a TransportMode, got " + repr_of(mode));
}

// sample_flags: a ReflTrans (an int in 0..3).
inline int sflags_arg(py::handle sf) {
    PyObject *o = sf.ptr();
    if (!PyLong_Check(o) || PyBool_Check(o)) value_error("sample_flags: must be a ReflTrans, got " + repr_of(sf));
    long v = PyLong_AsLong(o);
    if (PyErr_Occurred()) {
        PyErr_Clear();
        v = -1;
    }
    if (v < 0 || v > 3) value_error("sample_flags: must be a ReflTrans (0..3), got " + repr_of(sf));
    return int(v);
}

// An integer >= lo (and <= hi when hi >= lo), bool refused (numbers.Integral in Python's words).
inline long long int_arg(py::handle h, const char *name, long long lo, long long hi = -1) {
    PyObject *o = h.ptr();
    if (PyBool_Check(o) || !PyIndex_Check(o)) type_error(std::string(name) + ": expected an integer, got " + type_name(h));
    py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(o));
    int overflow = 0;
    long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if (overflow < 0 || (!overflow && v < lo))
        value_error(std::string(name) + ": must be >= " + std::to_string(lo) + ", got " + std::string(py::str(i)));
    if (hi >= lo && (overflow > 0 || v > hi))
        value_error(std::string(name) + ": must be <= " + std::to_string(hi) + ", got " + std::string(py::str(i)));
    if (overflow > 0) return LLONG_MAX;
    return v;
}

// A seed: a non-negative integer (used modulo 2**64), or None for one drawn from the system's entropy.
inline uint64_t seed_arg(py::handle h) {
    if (h.is_none()) {
        std::random_device rd;
        return (uint64_t(rd()) << 32) ^ uint64_t(rd());
    }
    PyObject *o = h.ptr();
    if (PyBool_Check(o) || !PyIndex_Check(o)) type_error("seed: expected a non-negative integer or None, got " + type_name(h));
    py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(o));
    if (PyObject_RichCompareBool(i.ptr(), py::int_(0).ptr(), Py_LT) == 1)
        value_error("seed: must be >= 0 (or None), got " + std::string(py::str(i)));
    return uint64_t(PyLong_AsUnsignedLongLongMask(i.ptr()));
}

// eval's / pdf's out= in numpy's words (an ndarray of this call's dtype and shape, writeable,
// C-contiguous, or for eval over a 1-D batch Fortran-ordered (N, 3) planes). Returns whether it
// is Fortran-ordered.
inline bool check_out(py::handle out, const Shape &shape, int type, bool fortran_ok, const char *name = "out") {
    const std::string n(name);
    if (!is_ndarray(out)) type_error(n + ": expected a numpy.ndarray, got " + type_name(out));
    py::array o = py::reinterpret_borrow<py::array>(out);
    py::dtype want(type);
    if (!o.dtype().is(want) && !(o.dtype().num() == want.num() && o.dtype().byteorder() != '>'))
        type_error(n + ": dtype must be " + std::string(py::str(want)) + " for these inputs, got " +
                   std::string(py::str(o.dtype())));
    if (shape_of(o) != shape) value_error(n + ": shape must be " + shape_repr(shape) + ", got " + shape_repr(shape_of(o)));
    bool wr = o.writeable();
    if (fortran_ok && wr && (o.flags() & py::array::f_style) && !(o.flags() & py::array::c_style)) return true;
    if (!(o.flags() & py::array::c_style) || !wr)
        value_error(n + ": must be a writeable C-contiguous array" +
                    std::string(fortran_ok ? " or a writeable Fortran-order (N, 3) array" : ""));
    return false;
}

}  // namespace bsdfkit::py_bind::door
