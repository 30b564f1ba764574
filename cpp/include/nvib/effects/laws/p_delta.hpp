// P-delta: the geometric stiffness of a storey carrying the gravity load P above it, f = -(P / h) d
// on its drift d (h the storey height). A vertical load on a leaning storey pushes it further over,
// so this is a negative spring: with it a yielding storey can lose its lateral stability (Chopra,
// Dynamics of Structures, 4th ed., section 18.9; the linearised "leaning column").
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct PDelta : LawBase {
  static constexpr const char* key = "p_delta";
  static constexpr const char* doc = "P-delta geometric stiffness f = -(P / h) d on a storey drift d";
  static constexpr const char* source = "Chopra, Dynamics of Structures, section 18.9";
  static constexpr bool assembled = true;
  static constexpr std::array<Parameter, 2> parameters{
      {{"P", kRequired, "gravity load carried by the storey (compression > 0)"}, {"h", kRequired, "storey height"}}};
  struct Params {
    double kg;  // -P / h
  };
  static void validate(const double* x) {
    NVIB_CHECK(x[0] >= 0.0, "P", "the gravity load must be >= 0 (compression), got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] > 0.0, "h", "the storey height must be > 0, got " + detail::fmt(x[1]));
  }
  static Params prepare(const double* x, const Signal*) { return {-x[0] / x[1]}; }
  static double value(const Params& p, double d, double, double) { return p.kg * d; }
  static Slopes slopes(const Params& p, double, double, double) { return {p.kg, 0.0}; }
  static double potential(const Params& p, double d, double) { return 0.5 * p.kg * d * d; }
};

}  // namespace effects
}  // namespace nvib
