// The schemes and the Newton options, bound by one generic template from
// their declared parameters: constructor (positional reals, the rest by
// name, every error naming the argument), read-only parameters, key, label,
// orders, repr, equality, pickling, named constructors (factories).
#pragma once

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include <nvib/nvib.hpp>

#include "bind_types.hpp"

namespace nvib_py {

namespace param = nvib::param;
using nvib::Newton;

// ---- Python value -> parameter -------------------------------------------------------
inline double to_real(py::handle x, const std::string& name) {
  const py::module_ numbers = py::module_::import("numbers");
  if (py::isinstance<py::bool_>(x) || !py::isinstance(x, numbers.attr("Real")))
    raise_type_error(name, "expected a real number, got " + std::string(py::str(py::type::of(x).attr("__name__"))));
  try {
    return py::float_(py::reinterpret_borrow<py::object>(x)).cast<double>();
  } catch (py::error_already_set&) {  // an integer too large for a double
    raise_value_error(name, "must be finite, got an integer too large for a double");
  }
}

struct Convert {
  const char* owner;
  void operator()(double& x, const param::Real& p, py::handle v) const { x = to_real(v, p.name); }
  void operator()(int& x, const param::Int& p, py::handle v) const {
    const py::module_ numbers = py::module_::import("numbers");
    if (py::isinstance<py::bool_>(v) || !py::isinstance(v, numbers.attr("Integral")))
      raise_type_error(p.name, "expected an integer, got " + std::string(py::str(py::type::of(v).attr("__name__"))));
    const py::int_ i(py::reinterpret_borrow<py::object>(v));
    if (i < py::int_(p.lo) || i > py::int_(p.hi))
      raise_value_error(p.name, std::string(owner) + " needs " + p.bounds() + ", got " + std::string(py::str(i)));
    x = i.cast<int>();
  }
  template <class E>
  void operator()(E& x, const param::Choice& p, py::handle v) const {
    if (!py::isinstance<py::str>(v))
      raise_type_error(p.name, "expected one of " + p.listing() + ", got " +
                                   std::string(py::str(py::type::of(v).attr("__name__"))));
    const std::string s = v.cast<std::string>();
    if (s == "none" && p.index_of("one_iteration") >= 0)
      raise_value_error(p.name, "'none' is now 'one_iteration' (one Newton iteration on the full residual, then "
                                "accept) or 'incremental' (the textbook incremental format)");
    const int k = p.index_of(s);
    if (k < 0) raise_value_error(p.name, "expected " + p.listing() + ", got '" + s + "'");
    x = static_cast<E>(k);
  }
  void operator()(Newton& x, const param::NewtonOptions& p, py::handle v) const {
    if (!py::isinstance<Newton>(v))
      raise_type_error(p.name, "expected nvib.Newton(...), got " + std::string(py::str(py::type::of(v).attr("__name__"))));
    x = v.cast<Newton>();
  }
};

// ---- parameter -> Python value and description ------------------------------------------
inline py::object to_python(double x, const param::Real&) { return py::float_(x); }
inline py::object to_python(int x, const param::Int&) { return py::int_(x); }
template <class E>
py::object to_python(E x, const param::Choice& p) {
  return py::str(p[static_cast<int>(x)]);
}
inline py::object to_python(const Newton& x, const param::NewtonOptions&) { return py::cast(x); }

inline const char* kind_of(const param::Real&) { return "real"; }
inline const char* kind_of(const param::Int&) { return "int"; }
inline const char* kind_of(const param::Choice&) { return "choice"; }
inline const char* kind_of(const param::NewtonOptions&) { return "newton"; }
inline std::string bounds_of(const param::Real& p) { return p.bounds(); }
inline std::string bounds_of(const param::Int& p) { return p.bounds(); }
inline std::string bounds_of(const param::Choice& p) { return p.listing(); }
inline std::string bounds_of(const param::NewtonOptions&) { return ""; }
// The range as data: (lo, hi, lo_open, hi_open) for reals and integers, the names for choices.
inline py::object range_of(const param::Real& p) { return py::make_tuple(p.lo, p.hi, p.lo_open, p.hi_open); }
inline py::object range_of(const param::Int& p) { return py::make_tuple(p.lo, p.hi, false, false); }
inline py::object range_of(const param::Choice& p) {
  py::tuple names(static_cast<size_t>(p.count));
  for (int k = 0; k < p.count; ++k) names[static_cast<size_t>(k)] = py::str(p[k]);
  return names;
}
inline py::object range_of(const param::NewtonOptions&) { return py::none(); }
// The previous name of a renamed parameter (None if it was never renamed).
template <class P>
py::object formerly_of(const P& p) {
  if constexpr (std::is_same_v<P, param::Int> || std::is_same_v<P, param::Choice>) {
    if (p.formerly != nullptr) return py::str(p.formerly);
  }
  return py::none();
}

// Reals may be given by position (schemes only); everything else by name.
template <class S>
constexpr bool positional_reals() {
  return !std::is_same_v<S, Newton>;
}

// [{name, kind, default, doc, bounds, range, positional}] in declaration order; range is
// (lo, hi, lo_open, hi_open) for a real or an integer, the allowed names for a choice.
template <class S>
py::list describe() {
  py::list out;
  const S defaults{};
  S::parameters(defaults, [&](const auto& value, const auto& p) {
    py::dict d;
    d["name"] = p.name;
    d["kind"] = kind_of(p);
    d["default"] = to_python(value, p);
    d["doc"] = p.doc;
    d["bounds"] = bounds_of(p);
    d["range"] = range_of(p);
    d["positional"] = positional_reals<S>() && std::string(kind_of(p)) == "real";
    d["formerly"] = formerly_of(p);
    out.append(d);
  });
  return out;
}

template <class S>
std::string names_of(const py::list& params, bool positional_only) {
  std::string s;
  for (auto p : params)
    if (!positional_only || p["positional"].cast<bool>()) s += (s.empty() ? "" : ", ") + p["name"].cast<std::string>();
  return s;
}

// The constructor: positional reals, then keywords; iteration= is a shortcut for newton=Newton(iteration=...).
template <class S>
S construct(const py::args& args, const py::kwargs& kwargs) {
  const py::list params = describe<S>();
  std::vector<std::string> positional, all;
  for (auto p : params) {
    all.push_back(p["name"].cast<std::string>());
    if (p["positional"].cast<bool>()) positional.push_back(all.back());
  }
  if (args.size() > positional.size()) {
    std::string kw;
    for (auto& n : all)
      if (std::find(positional.begin(), positional.end(), n) == positional.end()) kw += (kw.empty() ? "" : ", ") + n;
    raise_type_error(S::name, "takes at most " + std::to_string(positional.size()) + " positional argument" +
                                  (positional.size() == 1 ? "" : "s") + " (" +
                                  (positional.empty() ? "none" : names_of<S>(params, true)) + "), got " +
                                  std::to_string(args.size()) + (kw.empty() ? "" : "; " + kw + " must be given by name"));
  }
  py::dict given;
  for (size_t i = 0; i < args.size(); ++i) given[py::str(positional[i])] = args[i];
  for (auto item : kwargs) {
    const std::string key = item.first.cast<std::string>();
    if (given.contains(item.first)) raise_type_error(key, std::string("given twice (by position and by name) to ") + S::name);
    const bool shortcut = key == "iteration" && nvib::has_newton<S>::value;
    if (!shortcut && std::find(all.begin(), all.end(), key) == all.end()) {
      for (auto p : params)
        if (!p["formerly"].is_none() && p["formerly"].cast<std::string>() == key)
          raise_type_error(key, "renamed " + p["name"].cast<std::string>() + " in " + S::name + " (" +
                                    p["doc"].cast<std::string>() + "): give " + p["name"].cast<std::string>() +
                                    "=" + std::string(py::str(item.second)));
      raise_type_error(key, std::string("unknown parameter of ") + S::name + " (expected " +
                                (all.empty() ? std::string("none") : names_of<S>(params, false)) + ")");
    }
    given[item.first] = item.second;
  }
  S s{};
  if constexpr (nvib::has_newton<S>::value) {
    if (given.contains("iteration")) {
      if (given.contains("newton"))
        raise_type_error("iteration", "give the iteration either as iteration= or as newton=Newton(iteration=...), not both");
      Newton::parameters(s.newton, [&](auto& field, const auto& p) {
        if constexpr (std::is_same_v<std::decay_t<decltype(p)>, param::Choice>) {
          if (std::string(p.name) != "iteration") return;
          Convert{S::name}(field, p, given["iteration"]);
        }
      });
    }
  }
  S::parameters(s, [&](auto& field, const auto& p) {
    if (given.contains(p.name)) Convert{S::name}(field, p, given[p.name]);
  });
  s.validate();
  return s;
}

template <class S>
py::dict state_of(const S& s) {
  py::dict d;
  S::parameters(s, [&](const auto& value, const auto& p) { d[p.name] = to_python(value, p); });
  return d;
}

template <class S>
std::string repr_of(const S& s) {
  if constexpr (std::is_same_v<S, Newton>)
    return nvib::newton_repr(s);
  else
    return nvib::scheme_repr(s);
}

// What schemes and Newton share: constructor, parameters, repr, equality, pickling.
template <class S>
py::class_<S> bind_parameters(py::module_& m) {
  py::class_<S> cls(m, S::name, S::doc);
  cls.def(py::init([](const py::args& a, const py::kwargs& k) { return construct<S>(a, k); }))
      .def_static("parameters", &describe<S>, "the declared parameters: name, kind, default, doc, bounds, range, positional")
      .def("__repr__", &repr_of<S>)
      // By value (so -0.0 == 0.0, as for floats), parameter by parameter.
      .def("__eq__", [](const S& a, py::object b) { return py::isinstance<S>(b) && state_of(a).equal(state_of(b.cast<S>())); })
      .def("__hash__", [](const S& s) { return py::hash(py::tuple(state_of(s).attr("values")())); })
      .def(py::pickle([](const S& s) { return state_of(s); },
                      [](const py::dict& d) { return construct<S>(py::args(), py::kwargs(d)); }));
  const S defaults{};
  S::parameters(defaults, [&](const auto&, const auto& p) {
    const std::string name = p.name;
    cls.def_property_readonly(p.name, [name](const S& s) {
      py::object out;
      S::parameters(s, [&](const auto& value, const auto& q) {
        if (name == q.name) out = to_python(value, q);
      });
      return out;
    });
  });
  return cls;
}

template <class S>
void bind_scheme(py::module_& m, py::list& keys) {
  auto cls = bind_parameters<S>(m);
  cls.attr("key") = S::key;
  cls.attr("is_explicit") = S::is_explicit;
  cls.def_property_readonly("name", &repr_of<S>, "the full name, every parameter given")
      .def_property_readonly("label", [](const S& s) { return nvib::scheme_label(s); },
                             "short name for tables and legends (with the Newton mode of an implicit scheme)")
      .def_property_readonly("short_label", &S::label, "the label without the Newton mode")
      .def_property_readonly("order_u", &S::order_u, "global order of accuracy of the displacement")
      .def_property_readonly("order_v", &S::order_v, "global order of accuracy of the reported velocity")
      .def_property_readonly(
          "adaptive", [](const S& s) { return nvib::cached_error_constants(s).available; },
          "whether solve(..., tol=) takes the scheme: it has a local control of its step (PIM has none)");
  if constexpr (nvib::has_newton<S>::value)
    cls.def_property_readonly("iteration", [](const S& s) { return nvib::to_string(s.newton.iteration); });
  py::list factories;
  if constexpr (nvib::has_factories<S>::value) {
    S::factories([&](const char* method, const param::Real& p, S (*make)(double, Newton)) {
      factories.append(py::dict(py::arg("method") = method, py::arg("parameter") = p.name, py::arg("doc") = p.doc));
      const std::string pname = p.name, owner = std::string(S::name) + "." + method;
      cls.def_static(
          method,
          [make, pname, owner](const py::args& args, py::kwargs kwargs) {
            if (args.size() > 1) raise_type_error(owner, "takes 1 positional argument (" + pname + "), got " +
                                                             std::to_string(args.size()));
            for (auto item : kwargs) {  // unknown names first, as Python does
              const std::string key = item.first.cast<std::string>();
              if (key != pname && key != "newton" && key != "iteration")
                raise_type_error(key, "unknown parameter of " + owner + " (expected " + pname + ", newton, iteration)");
            }
            if (args.size() == 1 && kwargs.contains(pname.c_str()))
              raise_type_error(pname, "given twice (by position and by name) to " + owner);
            if (args.empty() && !kwargs.contains(pname.c_str())) raise_type_error(pname, "missing (required by " + owner + ")");
            const py::object value = args.size() == 1 ? py::object(args[0]) : py::object(kwargs[pname.c_str()]);
            const double x = to_real(value, pname);
            if (kwargs.contains(pname.c_str())) PyDict_DelItemString(kwargs.ptr(), pname.c_str());
            const S options = construct<S>(py::args(), kwargs);  // only the Newton options
            return make(x, options.newton);
          },
          p.doc);
    });
  }
  cls.def_static("factories", [factories]() { return factories.attr("copy")(); },
                 "the named constructors: method, its one parameter, doc");
  keys.append(py::make_tuple(S::key, cls));
}

inline void bind_schemes(py::module_& m) {
  bind_parameters<Newton>(m)
      .def_property_readonly("accepts_unconverged", &Newton::accepts_unconverged,
                             "True for the modes that accept a step without an equilibrium check");
  py::list keys;
  nvib::AllSchemes::for_each([&](auto* tag) { bind_scheme<std::remove_pointer_t<decltype(tag)>>(m, keys); });
  m.attr("SCHEMES") = py::tuple(keys);
}

// Calls fn(scheme) with the scheme's C++ type; a non-scheme raises TypeError naming `argument`.
template <class Fn>
py::object with_scheme(py::handle scheme, const char* argument, Fn&& fn) {
  bool done = false;
  py::object out;
  nvib::AllSchemes::for_each([&](auto* tag) {
    using S = std::remove_pointer_t<decltype(tag)>;
    if (!done && py::isinstance<S>(scheme)) {
      done = true;
      out = fn(scheme.cast<const S&>());
    }
  });
  if (!done) {
    std::string names;
    nvib::AllSchemes::for_each([&](auto* tag) {
      names += (names.empty() ? "" : ", ") + std::string(std::remove_pointer_t<decltype(tag)>::name);
    });
    raise_type_error(argument, "expected a scheme (" + names + "), got " +
                                   std::string(py::str(py::type::of(scheme).attr("__name__"))));
  }
  return out;
}

}  // namespace nvib_py
