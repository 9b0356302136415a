// Per-element parameters at the binding (issue 47; kernels in bsdfkit/batch_varying.h). A model's
// keyword constructor takes a numpy array for any real field (shape (...) ) or RGB field (shape
// (..., 3)); the array is kept as a float64 C-order plane and the field's uniform value is the
// array's first element (so the bound model always has one valid uniform instance). Integer,
// boolean, enum and table fields take one value for the whole material. At call time the
// planes' shapes broadcast with the directions' (numpy rules): the batch is their broadcast.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <string>
#include <vector>

#include "bsdfkit/batch_varying.h"
#include "door.h"

namespace bsdfkit::py_bind {

namespace py = pybind11;

// One varying field of a bound model.
struct VaryingField {
    int field = 0;          // index in the Params walk
    int comps = 1;          // 1 (real) or 3 (RGB)
    std::string name;       // "Model.field" in messages, field in `params`
    py::array values;       // float64, C order, read-only: shape + (3,) for RGB
    door::Shape shape;      // the parameter's batch shape (the values' shape without the RGB axis)
};

namespace varying_detail {

// numpy's multi-index of flat element k of shape s, as "(i, j)".
inline std::string index_repr(const door::Shape &s, py::ssize_t k) {
    door::Shape idx(s.size());
    for (size_t d = s.size(); d-- > 0;) {
        idx[d] = s[d] ? k % s[d] : 0;
        k = s[d] ? k / s[d] : 0;
    }
    std::string r = "(";
    for (size_t d = 0; d < idx.size(); ++d) r += (d ? ", " : "") + std::to_string(idx[d]);
    return r + (idx.size() == 1 ? ",)" : ")");
}

}  // namespace varying_detail

// Whether a keyword value is an array for a real (comps 1) or RGB (comps 3) field: a numpy array
// of at least 1 (real) or 2 (RGB, last axis 3) dimensions. A 0-d array or a (3,) RGB is uniform.
inline bool is_plane_value(const py::handle &h, int comps) {
    if (!door::is_ndarray(h)) return false;
    py::array a = py::reinterpret_borrow<py::array>(h);
    return comps == 1 ? a.ndim() >= 1 : a.ndim() >= 2;
}

// The plane of field `index` from a numpy array: float64, C order, checked (real dtype, RGB last
// axis 3, every value finite, naming the field and the first bad index). Sets `first` to the first
// element's value (the uniform instance's) when the array is not empty.
inline VaryingField make_plane(const py::handle &h, int index, int comps, const std::string &what, double *first) {
    py::array a = py::reinterpret_borrow<py::array>(h);
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::type_error(what + ": expected a real numeric array, got dtype " + std::string(py::str(a.dtype())));
    if (comps == 3 && a.shape(a.ndim() - 1) != 3)
        throw py::value_error(what + ": an RGB array needs a last axis of length 3, got shape " +
                              door::shape_repr(door::shape_of(a)));
    py::array_t<double, py::array::c_style | py::array::forcecast> v(a);
    VaryingField f;
    f.field = index;
    f.comps = comps;
    f.name = what;
    f.shape = door::shape_of(v);
    if (comps == 3) f.shape.pop_back();
    const double *d = v.data();
    const py::ssize_t n = v.size();
    for (py::ssize_t k = 0; k < n; ++k)
        if (!std::isfinite(d[k])) {
            const py::ssize_t e = k / comps;
            throw py::value_error(what + ": must be finite, got " + std::string(py::str(py::float_(d[k]))) +
                                  " at index " + varying_detail::index_repr(f.shape, e) +
                                  (comps == 3 ? " channel " + std::to_string(k % 3) : ""));
        }
    for (int c = 0; c < comps && n > 0; ++c) first[c] = d[c];
    // read-only: the model is a value, its parameters cannot change under it
    v.attr("setflags")(py::arg("write") = false);
    f.values = std::move(v);
    return f;
}

// The planes broadcast to a call's batch: float64 C-order arrays of batch + (comps,) (a view when
// the shape is already the batch's, else numpy's broadcast_to copied), kept alive in `keep`.
inline std::vector<ParamPlane> planes_for(const std::vector<VaryingField> &fields, const door::Shape &batch,
                                          std::vector<py::array> &keep) {
    std::vector<ParamPlane> planes;
    keep.clear();
    for (const VaryingField &f : fields) {
        door::Shape target = batch;
        if (f.comps == 3) target.push_back(3);
        py::array a = f.values;
        if (door::shape_of(a) != target)
            a = py::array_t<double, py::array::c_style | py::array::forcecast>(
                py::module_::import("numpy").attr("broadcast_to")(f.values, door::to_tuple(target)));
        keep.push_back(a);
        planes.push_back({f.field, f.comps, static_cast<const double *>(a.data())});
    }
    return planes;
}

// numpy broadcasting of the call's argument shapes with the varying fields' (named in the error).
inline door::Shape broadcast_with(const std::vector<std::string> &names, const std::vector<door::Shape> &shapes,
                                  const std::vector<VaryingField> &fields) {
    std::vector<std::string> n = names;
    std::vector<door::Shape> s = shapes;
    for (const VaryingField &f : fields) {
        n.push_back(f.name);
        s.push_back(f.shape);
    }
    size_t nd = 0;
    for (auto &x : s) nd = std::max(nd, x.size());
    door::Shape r(nd, 1);
    for (size_t a = 0; a < s.size(); ++a)
        for (size_t k = 0; k < s[a].size(); ++k) {
            py::ssize_t &d = r[nd - s[a].size() + k];
            const py::ssize_t v = s[a][k];
            if (d == 1) d = v;
            else if (v != 1 && v != d) {
                // name the first argument whose shape clashes, and the one it clashes with
                size_t other = 0;
                const size_t axis = nd - s[a].size() + k;  // counted in the broadcast shape
                for (size_t b = 0; b < a; ++b) {
                    const size_t off = nd - s[b].size();
                    if (axis >= off && s[b][axis - off] != 1 && s[b][axis - off] != v) {
                        other = b;
                        break;
                    }
                }
                throw py::value_error(n[a] + " and " + n[other] + ": shapes cannot be broadcast together (" + n[a] +
                                      " " + door::shape_repr(s[a]) + ", " + n[other] + " " +
                                      door::shape_repr(s[other]) + ")");
            }
        }
    return r;
}

}  // namespace bsdfkit::py_bind
