// A ground acceleration a_g(t): the load P = -M r a_g(t) on every DOF that moves with the ground
// (r the measure, 1 on those DOFs); the model's displacements are then relative to the ground.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

// P = -M r a_g(t): the measure's g is r, turned into M r when the effects are built.
struct GroundAcceleration : LawBase {
  static constexpr const char* key = "ground_acceleration";
  static constexpr const char* doc = "ground acceleration a_g(t): load P = -M r a_g(t), r the measure";
  static constexpr bool uses_displacement = false, is_load = true;
  static constexpr std::array<Parameter, 0> parameters{};
  static constexpr const char* signal = "signal";
  static constexpr bool signal_required = true;
  struct Params {
    const Signal* a_g;
  };
  static Params prepare(const double*, const Signal* s) { return {s}; }
  static double value(const Params& p, double, double, double t) { return p.a_g->value(t); }  // g^T f = -P
  static Slopes slopes(const Params&, double, double, double) { return {}; }
  static bool uses_time(const Params&) { return true; }
};

}  // namespace effects
}  // namespace nvib
