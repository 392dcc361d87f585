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
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "revcol/error.hpp"
#include "revcol/interrupt.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::bind {

/// A Python object standing for an integer argument, converted in the function body.
struct [[gnu::visibility("hidden")]] PyInt {
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
struct [[gnu::visibility("hidden")]] PyReal {
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

/// A Python object standing for a string argument, converted in the function body.
struct [[gnu::visibility("hidden")]] PyStr {
  pybind11::object o;  ///< the argument as given
};

/// x as a std::string (a Python str only); a TypeError naming `what` otherwise.
inline std::string to_str(const PyStr& x, const std::string& what) {
  if (!pybind11::isinstance<pybind11::str>(x.o))
    throw pybind11::type_error(what + " must be a string, got " +
                               std::string(pybind11::str(pybind11::type::handle_of(x.o).attr("__name__"))));
  return x.o.cast<std::string>();
}

/// A Python object standing for a float64 array argument, converted in the function body.
struct [[gnu::visibility("hidden")]] ArrayArg {
  pybind11::object o;  ///< the argument as given
};

/// x as a C-contiguous float64 array (numpy's conversion: any array, nested sequence or number);
/// a TypeError naming `what` when numpy cannot convert it.
inline pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast> to_array(
    const ArrayArg& x, const std::string& what) {
  using A = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
  A a = A::ensure(x.o);  // empty (error cleared) when numpy cannot convert
  if (!a)
    throw pybind11::type_error(what + " must be an array of real numbers, got " +
                               std::string(pybind11::str(pybind11::type::handle_of(x.o).attr("__name__"))));
  return a;
}

/// As to_array, for an optional argument (None gives nullopt).
inline std::optional<pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>> to_array(
    const std::optional<ArrayArg>& x, const std::string& what) {
  if (!x) return std::nullopt;
  return to_array(*x, what);
}

/// f() (the reading of checkpoint entry `key`), with any conversion failure (pybind11's
/// "Unable to cast", a numpy TypeError/ValueError) turned into an InvalidArgument naming the entry.
template <class F>
auto checkpoint_entry(const std::string& key, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const pybind11::cast_error&) {
    throw InvalidArgument("checkpoint entry '" + key + "' has the wrong type or range for its field");
  } catch (pybind11::error_already_set& e) {
    if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError) && !e.matches(PyExc_OverflowError)) throw;
    throw InvalidArgument("checkpoint entry '" + key + "' has the wrong type or range (" + e.what() + ")");
  }
}

/// A checkpoint entry converted to T; an InvalidArgument naming the entry when it does not fit.
template <class T>
T checkpoint_field(pybind11::handle obj, const std::string& key) {
  try {
    return checkpoint_entry(key, [&] { return pybind11::cast<T>(obj); });
  } catch (const InvalidArgument& e) {  // say what was there
    throw InvalidArgument(std::string(e.what()) + ": got " +
                          std::string(pybind11::str(pybind11::type::handle_of(obj).attr("__name__"))) + " " +
                          std::string(pybind11::repr(obj)).substr(0, 60));
  }
}

/// A checkpoint array entry as a flat std::vector<T>, strictly: an integer field takes an
/// integer (or bool) array whose every value fits T, a real field takes an integer or float
/// array; anything else (strings, objects, floats in an integer field, -1 in a count) is an
/// InvalidArgument naming the entry. (numpy's forcecast would turn NaN into a count silently.)
template <class T>
std::vector<T> checkpoint_array(pybind11::handle obj, const std::string& key) {
  namespace py = pybind11;
  const py::array a = py::array::ensure(obj);
  require(static_cast<bool>(a), [&] { return "checkpoint entry '" + key + "' is not an array"; });
  const char kind = a.dtype().kind();
  const auto dtype = [&] { return std::string(py::str(a.dtype())); };
  if constexpr (std::is_integral_v<T>) {
    require(kind == 'i' || kind == 'u' || kind == 'b',
            [&] { return "checkpoint entry '" + key + "' must hold integers, got dtype " + dtype(); });
    std::vector<T> out(static_cast<std::size_t>(a.size()));
    const auto fits = [&](auto q) {
      return std::in_range<T>(q) ? true : (throw InvalidArgument("checkpoint entry '" + key + "' holds " +
                                                                 std::to_string(q) + ", outside its type's range"), false);
    };
    if (kind == 'u') {
      const auto u = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>::ensure(a);
      for (py::ssize_t k = 0; k < u.size(); ++k) out[k] = fits(u.data()[k]) ? static_cast<T>(u.data()[k]) : T{};
    } else {
      const auto s = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
      for (py::ssize_t k = 0; k < s.size(); ++k) out[k] = fits(s.data()[k]) ? static_cast<T>(s.data()[k]) : T{};
    }
    return out;
  } else {
    require(kind == 'f' || kind == 'i' || kind == 'u',
            [&] { return "checkpoint entry '" + key + "' must hold numbers, got dtype " + dtype(); });
    const auto f = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
    return std::vector<T>(f.data(), f.data() + f.size());
  }
}

/// Set while a Ctrl-C that revcol.progress.Interrupt counted is unhandled (_core.request_stop);
/// read and written with the GIL held. That handler swallows the signal, so PyErr_CheckSignals
/// alone returns 0 and a run that never reaches its progress callback (one particle: no
/// collisions) would go on after the press (issue 59).
inline bool& stop_requested() {
  static bool flag = false;
  return flag;
}

/// A long run's poll (engine::Poll): false once a signal handler (Ctrl-C) left a Python
/// exception pending, the run stops at a valid point and the caller raises it; or once a
/// counted Ctrl-C asked runs to stop, the run stops there and returns as at its end.
inline bool poll_signals() { return PyErr_CheckSignals() == 0 && !stop_requested(); }

/// An interrupt check (revcol/interrupt.hpp) for a loop that holds the GIL (a relaxed random
/// start): stop once Ctrl-C left a KeyboardInterrupt pending (the translator raises it).
inline InterruptCheck held_signal_check() {
  return [] { return PyErr_CheckSignals() != 0; };
}

/// A study's interrupt check (revcol/interrupt.hpp) for a loop that runs with the GIL
/// released: takes the GIL and says stop once Ctrl-C left a KeyboardInterrupt pending (the
/// module's translator of revcol::Interrupted then raises it).
inline InterruptCheck released_signal_check() {
  return [] {
    pybind11::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  };
}

}  // namespace revcol::bind

namespace pybind11::detail {
// One caster per argument type: it loads any object (the body converts it, naming the argument)
// and shows `name` in signatures, the same text as pybind11's own caster of that type.
#define REVCOL_OBJECT_ARG_CASTER(Type, name)                                   \
  template <>                                                                  \
  struct type_caster<revcol::bind::Type> {                                     \
    PYBIND11_TYPE_CASTER(revcol::bind::Type, name);                            \
    bool load(handle src, bool) {                                              \
      if (!src) return false; /* optional<Type> turns None into nullopt first */ \
      value.o = reinterpret_borrow<object>(src);                               \
      return true;                                                             \
    }                                                                          \
    static handle cast(const revcol::bind::Type& x, return_value_policy, handle) { return x.o.inc_ref(); } \
  };
REVCOL_OBJECT_ARG_CASTER(PyInt, io_name("typing.SupportsInt | typing.SupportsIndex", "int"))
REVCOL_OBJECT_ARG_CASTER(PyReal, io_name("typing.SupportsFloat | typing.SupportsIndex", "float"))
REVCOL_OBJECT_ARG_CASTER(PyStr, const_name("str"))
REVCOL_OBJECT_ARG_CASTER(ArrayArg, io_name("typing.Annotated[numpy.typing.ArrayLike, numpy.float64]",
                                           "numpy.typing.NDArray[numpy.float64]"))
#undef REVCOL_OBJECT_ARG_CASTER
}  // namespace pybind11::detail
