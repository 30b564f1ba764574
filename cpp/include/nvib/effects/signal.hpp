// Time signals of the effects: a ground acceleration a_g(t), a rail irregularity r(t).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../base/errors.hpp"

namespace nvib {
namespace effects {

// A time signal: absent (0), a sine, or a table interpolated linearly (0 outside its range).
struct Signal {
  enum class Kind { none, sine, table };
  Kind kind = Kind::none;
  double amplitude = 0.0, omega = 0.0, phase = 0.0;
  std::vector<double> t, y;
  double inv_spacing = 0.0;  // (knots - 1) / span: a first guess of a time's segment

  static Signal sine(double amplitude, double omega, double phase = 0.0) {
    NVIB_CHECK(std::isfinite(amplitude) && std::isfinite(omega) && std::isfinite(phase), "signal",
               "amplitude, omega and phase must be finite");
    Signal s;
    s.kind = Kind::sine;
    s.amplitude = amplitude;
    s.omega = omega;
    s.phase = phase;
    return s;
  }
  static Signal table(std::vector<double> times, std::vector<double> values) {
    NVIB_CHECK(times.size() == values.size(), "signal", "t and values must have the same length");
    NVIB_CHECK(times.size() >= 2, "signal", "a table needs at least two points");
    for (size_t i = 0; i < times.size(); ++i) {
      NVIB_CHECK(std::isfinite(times[i]) && std::isfinite(values[i]), "signal", "non-finite table entry");
      if (i > 0) NVIB_CHECK(times[i] > times[i - 1], "signal", "table times must increase strictly");
    }
    Signal s;
    s.kind = Kind::table;
    s.t = std::move(times);
    s.y = std::move(values);
    s.inv_spacing = static_cast<double>(s.t.size() - 1) / (s.t.back() - s.t.front());
    return s;
  }

  bool present() const { return kind != Kind::none; }
  // Whether its rate jumps (at a table's knots): then derivative() depends on the side.
  bool rate_jumps() const { return kind == Kind::table; }

  double value(double time) const {
    switch (kind) {
      case Kind::none: return 0.0;
      case Kind::sine: return amplitude * std::sin(omega * time + phase);
      case Kind::table: {
        if (time < t.front() || time > t.back()) return 0.0;
        const size_t i = segment(time);
        const double w = (time - t[i]) / (t[i + 1] - t[i]);
        return (1.0 - w) * y[i] + w * y[i + 1];
      }
    }
    return 0.0;
  }
  // The rate of the signal at `time`. A table's slope jumps at its knots; there (to round-off: a step's
  // time n h may miss a knot by an ulp) `side` chooses the limit: -1 from the left (the end of the step
  // before), +1 from the right (the start of the step after), 0 their mean (the first knot: the slope
  // inside). The energy accounting integrates the power by the trapezoidal rule, step by step: the end of
  // a step takes the left limit and the start of the next the right one, so a kink on a step point costs
  // O(h^2) like any other point, where one value for both would leave an O(h) error (once in the sum with
  // a one-sided value, or at that instant with the mean).
  double derivative(double time, int side = 0) const {
    switch (kind) {
      case Kind::none: return 0.0;
      case Kind::sine: return amplitude * omega * std::cos(omega * time + phase);
      case Kind::table: {
        const double tol = 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(time));
        if (time < t.front() || time > t.back() + tol) return 0.0;
        const size_t i = segment(time);
        const size_t k = time - t[i] <= t[i + 1] - time ? i : i + 1;  // the nearest knot
        if (k > 0 && std::abs(time - t[k]) <= tol) {
          const double left = slope_of(k - 1), right = slope_of(k);
          return side < 0 ? left : side > 0 ? right : 0.5 * (left + right);
        }
        if (time > t.back()) return 0.0;
        return slope_of(i);
      }
    }
    return 0.0;
  }

 private:
  // The slope of segment k (from t[k] to t[k + 1]); 0 past the last knot.
  double slope_of(size_t k) const { return k + 1 < t.size() ? (y[k + 1] - y[k]) / (t[k + 1] - t[k]) : 0.0; }
  // The segment i with t[i] <= time < t[i + 1] (the first or last for a time outside): guessed from
  // the mean spacing and walked to the right one, O(1) for a record's evenly spaced samples (a binary
  // search over a 3000-sample record cost as much as the rest of a small model's force).
  size_t segment(double time) const {
    const size_t last = t.size() - 2;
    const double guess = (time - t.front()) * inv_spacing;
    size_t i = !(guess > 0.0) ? 0 : guess >= static_cast<double>(last) ? last : static_cast<size_t>(guess);
    while (i > 0 && t[i] > time) --i;
    while (i < last && t[i + 1] <= time) ++i;
    return i;
  }
};

}  // namespace effects
}  // namespace nvib
