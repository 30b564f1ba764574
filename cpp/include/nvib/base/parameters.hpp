// Declared parameters: a scheme (or the Newton options) lists its parameters
// once, through a visitor, with their names, documentation and ranges:
//
//   template <class Self, class V> static void parameters(Self& s, V&& v) {
//     v(s.eta, param::real("eta", "weight of a_{n-1}").range(0.0, 1.0));
//   }
//
// The defaults are the values of a default-constructed struct. The binding,
// the command line and the checks below are generated from this list.
#pragma once

#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>

#include "errors.hpp"

namespace nvib {
namespace param {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Real {
  const char* name;
  const char* doc;
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;
  const char* note = "";  // why the range is what it is, appended to the message

  constexpr Real range(double a, double b) const { return with(a, b, false, false); }
  constexpr Real above(double a) const { return with(a, hi, true, hi_open); }
  constexpr Real at_least(double a) const { return with(a, hi, false, hi_open); }
  constexpr Real at_most(double b) const { return with(lo, b, lo_open, false); }
  constexpr Real because(const char* why) const {
    Real r = *this;
    r.note = why;
    return r;
  }
  bool contains(double x) const {
    return std::isfinite(x) && (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  // "0 <= eta <= 1", "beta > 0"
  std::string bounds() const {
    std::string s;
    const bool has_lo = lo > -kInf, has_hi = hi < kInf;
    if (has_lo && has_hi) return detail::fmt(lo) + (lo_open ? " < " : " <= ") + name + (hi_open ? " < " : " <= ") +
                                 detail::fmt(hi);
    if (has_lo) return std::string(name) + (lo_open ? " > " : " >= ") + detail::fmt(lo);
    if (has_hi) return std::string(name) + (hi_open ? " < " : " <= ") + detail::fmt(hi);
    return "a finite " + std::string(name);
  }

 private:
  constexpr Real with(double a, double b, bool ao, bool bo) const {
    Real r = *this;
    r.lo = a;
    r.hi = b;
    r.lo_open = ao;
    r.hi_open = bo;
    return r;
  }
};

struct Int {
  const char* name;
  const char* doc;
  int lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  const char* formerly = nullptr;  // the parameter's previous name, refused with a message naming the new one
  constexpr Int range(int a, int b) const {
    Int r = *this;
    r.lo = a;
    r.hi = b;
    return r;
  }
  constexpr Int renamed_from(const char* old) const {
    Int r = *this;
    r.formerly = old;
    return r;
  }
  bool contains(int x) const { return x >= lo && x <= hi; }
  std::string bounds() const { return std::to_string(lo) + " <= " + name + " <= " + std::to_string(hi); }
};

// An enum parameter: value k of the enum is names[k].
struct Choice {
  static constexpr int kMax = 8;
  const char* name;
  const char* doc;
  std::array<const char*, kMax> names{};
  int count = 0;
  const char* formerly = nullptr;  // the parameter's previous name, refused with a message naming the new one
  Choice renamed_from(const char* old) const {
    Choice r = *this;
    r.formerly = old;
    return r;
  }
  const char* operator[](int k) const { return k >= 0 && k < count ? names[static_cast<size_t>(k)] : "?"; }
  int index_of(const std::string& s) const {
    for (int k = 0; k < count; ++k)
      if (s == names[static_cast<size_t>(k)]) return k;
    return -1;
  }
  std::string listing() const {  // 'a', 'b' or 'c'
    std::string s;
    for (int k = 0; k < count; ++k)
      s += (k == 0 ? "'" : (k + 1 == count ? " or '" : ", '")) + std::string(names[static_cast<size_t>(k)]) + "'";
    return s;
  }
};

// The Newton options of an implicit scheme (a nvib::Newton).
struct NewtonOptions {
  const char* name;
  const char* doc;
};

constexpr Real real(const char* name, const char* doc) { return Real{name, doc}; }
constexpr Int integer(const char* name, const char* doc) { return Int{name, doc}; }
inline Choice choice(const char* name, const char* doc, std::initializer_list<const char*> names) {
  Choice c{name, doc};
  for (const char* n : names) c.names[static_cast<size_t>(c.count++)] = n;
  return c;
}
constexpr NewtonOptions newton(const char* name, const char* doc) { return NewtonOptions{name, doc}; }

namespace detail_ {
struct RangeChecker {
  const char* owner;
  void operator()(double x, const Real& p) const {
    NVIB_CHECK(p.contains(x), p.name,
               std::string(owner) + " needs " + p.bounds() + (*p.note ? std::string(" (") + p.note + ")" : "") +
                   ", got " + detail::fmt(x));
  }
  void operator()(int x, const Int& p) const {
    NVIB_CHECK(p.contains(x), p.name, std::string(owner) + " needs " + p.bounds() + ", got " + std::to_string(x));
  }
  template <class T, class P>
  void operator()(const T&, const P&) const {}
};
}  // namespace detail_

// Checks every Real and Int parameter of s against its declared range; the
// message names the parameter, the owner and the range.
template <class S>
void check_ranges(const S& s) {
  S::parameters(s, detail_::RangeChecker{S::name});
}

}  // namespace param
}  // namespace nvib
