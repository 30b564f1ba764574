// Linear spring f = k d.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Spring : LawBase {
  static constexpr const char* key = "spring";
  static constexpr const char* doc = "linear spring f = k d";
  static constexpr bool assembled = true;
  static constexpr std::array<Parameter, 1> parameters{{{"k", kRequired, "stiffness"}}};
  struct Params {
    double k;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0]}; }
  static double value(const Params& p, double d, double, double) { return p.k * d; }
  static Slopes slopes(const Params& p, double, double, double) { return {p.k, 0.0}; }
  static double potential(const Params& p, double d, double) { return 0.5 * p.k * d * d; }
};

}  // namespace effects
}  // namespace nvib
