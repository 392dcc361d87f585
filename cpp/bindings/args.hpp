// Integer and real arguments with messages that name them (issue 17).
//
// pybind11's own int caster refuses -1 for an unsigned parameter, 2^40 for an int and "3" for
// anything with one generic TypeError ("incompatible function arguments ...") that names no
// argument and no range. A parameter of type PyInt instead accepts any Python object; the
// function body converts it with to_int(x, "name", lo, hi), which raises
//   - TypeError  "name must be an integer, got float" for an object without __index__,
//   - ValueError "name = -1 is outside [0, 18446744073709551615]" (revcol::InvalidArgument)
//     for an integer out of range,
// before anything is built or changed. PyReal is the same for a double: to_real(x, "name")
// raises TypeError "name must be a real number, got str". Signatures and stubs still read
// "typing.SupportsInt | typing.SupportsIndex" and "typing.SupportsFloat | typing.SupportsIndex",
// as for pybind11's int and float.
#pragma once
#include <pybind11/pybind11.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "revcol/error.hpp"

namespace revcol::bind {

/// A Python object standing for an integer argument, converted in the function body.
struct PyInt {
  pybind11::object o;  ///< the argument as given
};

/// The integer value of x (anything with __index__, bool included) in [lo, hi]; a TypeError or
/// InvalidArgument naming `what` otherwise.
template <class T>
T to_int(const PyInt& x, const std::string& what, T lo = std::numeric_limits<T>::min(),
         T hi = std::numeric_limits<T>::max()) {
  PyObject* index = PyNumber_Index(x.o.ptr());
  if (index == nullptr) {
    PyErr_Clear();
    std::string hint;  // 1e6 is a float: say how to write it
    if (PyFloat_Check(x.o.ptr())) hint = " (" + std::string(pybind11::repr(x.o)) + "; write int(...) or 1_000_000)";
    throw pybind11::type_error(what + " must be an integer, got " +
                               std::string(pybind11::str(pybind11::type::handle_of(x.o).attr("__name__"))) + hint);
  }
  const auto value = pybind11::reinterpret_steal<pybind11::object>(index);
  const auto range = [&] {
    return what + " = " + std::string(pybind11::str(value)) + " is outside [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "]";
  };
  if constexpr (std::is_signed_v<T>) {
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
    if (overflow != 0 || (v == -1 && PyErr_Occurred())) {
      PyErr_Clear();
      throw InvalidArgument(range());
    }
    if (v < static_cast<long long>(lo) || v > static_cast<long long>(hi)) throw InvalidArgument(range());
    return static_cast<T>(v);
  } else {
    const unsigned long long v = PyLong_AsUnsignedLongLong(value.ptr());
    if (v == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {  // negative or >= 2^64
      PyErr_Clear();
      throw InvalidArgument(range());
    }
    if (v < static_cast<unsigned long long>(lo) || v > static_cast<unsigned long long>(hi))
      throw InvalidArgument(range());
    return static_cast<T>(v);
  }
}

/// As to_int, for an optional argument (None gives nullopt).
template <class T>
std::optional<T> to_int(const std::optional<PyInt>& x, const std::string& what,
                        T lo = std::numeric_limits<T>::min(), T hi = std::numeric_limits<T>::max()) {
  if (!x) return std::nullopt;
  return to_int<T>(*x, what, lo, hi);
}

/// A Python object standing for a real argument, converted in the function body.
struct PyReal {
  pybind11::object o;  ///< the argument as given
};

/// The value of x as a double (anything with __float__ or __index__); a TypeError naming `what`
/// otherwise. Finiteness and ranges are the caller's checks.
inline double to_real(const PyReal& x, const std::string& what) {
  const double v = PyFloat_AsDouble(x.o.ptr());
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw pybind11::type_error(what + " must be a real number, got " +
                               std::string(pybind11::str(pybind11::type::handle_of(x.o).attr("__name__"))));
  }
  return v;
}

/// As to_real, for an optional argument (None gives nullopt).
inline std::optional<double> to_real(const std::optional<PyReal>& x, const std::string& what) {
  if (!x) return std::nullopt;
  return to_real(*x, what);
}

/// A long run's poll (engine::Poll): false once a signal handler (Ctrl-C) left a Python
/// exception pending; the run stops at a valid point and the caller raises it.
inline bool poll_signals() { return PyErr_CheckSignals() == 0; }

}  // namespace revcol::bind

namespace pybind11::detail {
/// Loads any object into PyInt (the body converts it, naming the argument); signatures show
/// the same type text as pybind11's int.
template <>
struct type_caster<revcol::bind::PyInt> {
  PYBIND11_TYPE_CASTER(revcol::bind::PyInt, io_name("typing.SupportsInt | typing.SupportsIndex", "int"));
  bool load(handle src, bool) {
    if (!src) return false;  // (std::optional<PyInt> turns None into nullopt before this)
    value.o = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const revcol::bind::PyInt& x, return_value_policy, handle) { return x.o.inc_ref(); }
};
/// Loads any object into PyReal; signatures show pybind11's float type text.
template <>
struct type_caster<revcol::bind::PyReal> {
  PYBIND11_TYPE_CASTER(revcol::bind::PyReal, io_name("typing.SupportsFloat | typing.SupportsIndex", "float"));
  bool load(handle src, bool) {
    if (!src) return false;
    value.o = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const revcol::bind::PyReal& x, return_value_policy, handle) { return x.o.inc_ref(); }
};
}  // namespace pybind11::detail
