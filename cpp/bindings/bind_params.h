// Keyword arguments <-> Params fields (core/bxdf.h): the conversions of the generic bindings
// (bind_all.h for the models, bind_spectral.h for their spectral forms). Each model is
// constructed from keyword arguments named exactly as its Params fields (Mitsuba's named plugin
// parameters are the pattern): a missing keyword keeps the Params default, an unknown keyword or
// a value of the wrong type raises TypeError naming it, a bad value (not finite, no such enum
// name) raises ValueError naming it.
#pragma once
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "bind_model.h"
#include "bsdfkit/core/bxdf.h"

namespace bsdfkit::py_bind {

namespace bind_detail {


[[noreturn]] inline void type_error(const std::string &msg) { throw py::type_error(msg); }

inline std::string type_name(const py::handle &h) { return py::str(py::type::of(h).attr("__name__")); }

// Python value -> field, one overload per field type core/bxdf.h allows. `what` is "Model.field".
inline void from_py(const py::handle &h, double &out, const std::string &what) {
    PyObject *o = h.ptr();
    if (PyBool_Check(o) || PyUnicode_Check(o) || PyBytes_Check(o) || !PyNumber_Check(o))
        type_error(what + ": expected a real number, got " + type_name(h));
    double v = PyFloat_AsDouble(o);
    if (v == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        type_error(what + ": expected a real number, got " + type_name(h));
    }
    if (!std::isfinite(v)) value_error(what + ": must be finite, got " + std::to_string(v));
    out = v;
}

inline void from_py(const py::handle &h, bool &out, const std::string &what) {
    py::detail::make_caster<bool> c;
    if (!c.load(h, false)) type_error(what + ": expected a bool, got " + type_name(h));
    out = py::detail::cast_op<bool>(c);
}

inline void from_py(const py::handle &h, int &out, const std::string &what) {
    PyObject *o = h.ptr();
    if (PyBool_Check(o) || !PyIndex_Check(o)) type_error(what + ": expected an integer, got " + type_name(h));
    long long v = PyLong_AsLongLong(o);
    if (PyErr_Occurred() || v < INT32_MIN || v > INT32_MAX) {
        PyErr_Clear();
        value_error(what + ": integer out of range");
    }
    out = int(v);
}

inline void from_py(const py::handle &h, std::array<double, 3> &out, const std::string &what) {
    PyObject *o = h.ptr();
    if (PyUnicode_Check(o) || PyBytes_Check(o) || !PySequence_Check(o))
        type_error(what + ": expected 3 real numbers (RGB), got " + type_name(h));
    py::sequence seq = py::reinterpret_borrow<py::sequence>(h);
    if (seq.size() != 3) value_error(what + ": expected 3 real numbers (RGB), got " + std::to_string(seq.size()));
    for (size_t i = 0; i < 3; ++i) from_py(seq[i], out[i], what + "[" + std::to_string(i) + "]");
}

template <typename E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
void from_py(const py::handle &h, E &out, const std::string &what) {
    constexpr auto names = enum_names(E{});
    auto choices = [&] {
        std::string s;
        for (size_t i = 0; i < names.size(); ++i) s += (i ? ", '" : "'") + std::string(names[i]) + "'";
        return s;
    };
    if (PyUnicode_Check(h.ptr())) {
        std::string v = py::cast<std::string>(h);
        for (size_t i = 0; i < names.size(); ++i)
            if (v == names[i]) {
                out = E(i);
                return;
            }
        value_error(what + ": must be one of " + choices() + ", got '" + v + "'");
    }
    int i = 0;
    from_py(h, i, what);
    if (i < 0 || i >= int(names.size()))
        value_error(what + ": must be one of " + choices() + " (or 0.." + std::to_string(names.size() - 1) + ")");
    out = E(i);
}

template <typename T> void from_py(const py::handle &h, SharedTable<T> &out, const std::string &what) {
    py::detail::make_caster<SharedTable<T>> c;
    if (!c.load(h, false))
        type_error(what + ": expected a _core." + std::string(py::str(py::type::of<SharedTable<T>>().attr("__name__"))) +
                   ", got " + type_name(h));
    out = py::detail::cast_op<SharedTable<T>>(c);
}

// Field -> Python value (for `params`): enums by name, RGB as a tuple, tables as the table object.
template <typename T> py::object to_py(const T &v) {
    if constexpr (std::is_enum_v<T>) return py::str(enum_names(T{})[size_t(v)]);
    else if constexpr (std::is_same_v<T, std::array<double, 3>>) return py::make_tuple(v[0], v[1], v[2]);
    else return py::cast(v);
}

template <typename Params> std::vector<std::string> field_names() {
    std::vector<std::string> names;
    Params p;
    p.fields([&](const char *name, auto &) { names.emplace_back(name); });
    return names;
}

inline std::string join(const std::vector<std::string> &v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
}

// Params from keyword arguments (see the top of this file). varying: where a real or RGB field
// may take a numpy array (per-element parameters, bind_varying.h), its plane is appended and the
// field takes the array's first element; nullptr refuses arrays (the spectral forms, for now).
template <typename Params>
Params params_from_kwargs(const char *model, const py::args &args, const py::kwargs &kw,
                          std::vector<VaryingField> *varying = nullptr) {
    const std::string m(model);
    if (args.size() != 0)
        type_error(m + ": takes keyword arguments only (" + join(field_names<Params>()) + ")");
    Params p;
    size_t used = 0;
    int index = 0;
    p.fields([&](const char *name, auto &field) {
        using T = std::decay_t<decltype(field)>;
        const std::string what = m + "." + name;
        if (kw.contains(name)) {
            py::object v = kw[name];
            constexpr int comps = std::is_same_v<T, double> ? 1 : std::is_same_v<T, std::array<double, 3>> ? 3 : 0;
            if constexpr (comps > 0) {
                if (is_plane_value(v, comps)) {
                    if (!varying) type_error(what + ": per-element parameters (arrays) are not supported here");
                    double first[3] = {0, 0, 0};
                    if constexpr (comps == 1) first[0] = field;
                    else first[0] = field[0], first[1] = field[1], first[2] = field[2];
                    varying->push_back(make_plane(v, index, comps, what, first));
                    if constexpr (comps == 1) field = first[0];
                    else field = {first[0], first[1], first[2]};
                } else {
                    from_py(v, field, what);
                }
            } else if constexpr (!is_shared_table<T>::value) {
                if (door::is_ndarray(v) && py::reinterpret_borrow<py::array>(v).ndim() >= 1)
                    type_error(what + ": takes one value for the whole material (a knob or a count), "
                                      "not a per-element array");
                from_py(v, field, what);
            } else {
                from_py(v, field, what);  // a table: its own type error
            }
            ++used;
        } else if constexpr (is_shared_table<T>::value) {
            type_error(m + ": missing required keyword argument '" + name + "'");
        }
        ++index;
    });
    if (used != kw.size()) {
        std::vector<std::string> known = field_names<Params>();
        for (auto item : kw) {
            std::string k = py::str(item.first);
            if (std::find(known.begin(), known.end(), k) == known.end())
                type_error(m + ": unexpected keyword argument '" + k + "' (fields: " + join(known) + ")");
        }
    }
    return p;
}

} // namespace bind_detail

} // namespace bsdfkit::py_bind
