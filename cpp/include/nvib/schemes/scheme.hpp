// What every scheme declares, and the registry type.
//
// A scheme is an immutable parameter struct:
//   static constexpr const char* name       its C++ and Python class name ("CEMDTS")
//   static constexpr const char* key        its command-line name ("cemdts")
//   static constexpr const char* doc        one paragraph for help texts
//   static constexpr bool is_explicit
//   template <class Self, class V> static void parameters(Self&, V&&)   see parameters.hpp
//   void validate() const                   names the parameter and the condition
//   std::string label() const               short name for tables and legends
//   int order_u() const, order_v() const    true global orders of u and of the reported v
//   template <class Model> using stepper = ...
// Optionally `template <class V> static void factories(V&&)`: named
// constructors from one real parameter, such as GeneralizedAlpha::from_rho_inf.
// Implicit schemes hold their Newton options in a member `newton`.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <utility>

#include "../base/parameters.hpp"
#include "../newton/options.hpp"

namespace nvib {

template <class... S>
struct SchemeList {
  static constexpr std::size_t size = sizeof...(S);
  // f(type_tag<S>{}) for each scheme, in order.
  template <class F>
  static void for_each(F&& f) {
    (f(static_cast<S*>(nullptr)), ...);
  }
};

template <class S, class = void>
struct has_newton : std::false_type {};
template <class S>
struct has_newton<S, std::void_t<decltype(std::declval<const S&>().newton)>> : std::true_type {};

template <class S, class = void>
struct has_factories : std::false_type {};
template <class S>
struct has_factories<S, std::void_t<decltype(S::factories(std::declval<void (*)(...)>()))>> : std::true_type {};

namespace detail {
// 0.25 and 0.6 as such, 1/6 rather than 0.1667 (for labels).
inline std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", x);
  if (std::strtod(buf, nullptr) == x) return fmt(x);
  for (int den = 2; den <= 12; ++den) {
    const double num = std::round(x * den);
    if (std::abs(x * den - num) < 1e-12 && 0 < std::abs(num) && std::abs(num) < den)
      return std::to_string(static_cast<long>(num)) + "/" + std::to_string(den);
  }
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

// Visitor writing "name=value" pairs; only_changed: those that differ from the default.
template <class S>
struct ReprWriter {
  std::string out;
  const S* defaults = nullptr;
  void add(const char* name, const std::string& value) {
    out += (out.empty() ? "" : ", ") + std::string(name) + "=" + value;
  }
  void operator()(double x, const param::Real& p) { add(p.name, repr(x)); }
  void operator()(int x, const param::Int& p) { add(p.name, std::to_string(x)); }
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  void operator()(E x, const param::Choice& p) {
    add(p.name, std::string("'") + p[static_cast<int>(x)] + "'");
  }
  void operator()(const Newton& x, const param::NewtonOptions& p);
};
}  // namespace detail

// "CEMDTS(eta=0.45)": every parameter, so that it reads back as the same scheme.
template <class S>
std::string scheme_repr(const S& s) {
  detail::ReprWriter<S> w;
  S::parameters(s, w);
  return std::string(S::name) + "(" + w.out + ")";
}

// "Newton(iteration='modified')": the iteration and the options that differ from the defaults.
inline std::string newton_repr(const Newton& n) {
  const Newton d;
  std::string s = std::string("Newton(iteration='") + to_string(n.iteration) + "'";
  if (n.max_iter != d.max_iter) s += ", max_iter=" + std::to_string(n.max_iter);
  if (n.rtol != d.rtol) s += ", rtol=" + detail::repr(n.rtol);
  if (n.atol != d.atol) s += ", atol=" + detail::repr(n.atol);
  if (n.jacobian != d.jacobian) s += std::string(", jacobian='") + to_string(n.jacobian) + "'";
  if (n.linear_solver != d.linear_solver) s += std::string(", linear_solver='") + to_string(n.linear_solver) + "'";
  return s + ")";
}

template <class S>
void detail::ReprWriter<S>::operator()(const Newton& x, const param::NewtonOptions& p) {
  add(p.name, newton_repr(x));
}

// The label with the Newton mode of an implicit scheme: "Newmark (modified)".
template <class S>
std::string scheme_label(const S& s, bool with_iteration = true) {
  if constexpr (has_newton<S>::value)
    if (with_iteration) return s.label() + " (" + to_string(s.newton.iteration) + ")";
  return s.label();
}

}  // namespace nvib
