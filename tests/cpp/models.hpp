// Models shared by the C++ tests.
#pragma once

#include <nvib/nvib.hpp>

namespace nvib_test {

// The paper's hardening oscillator force 100 (1 + 30 u^2) u on one DOF, with its tangent.
struct Hardening {
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::VecRef out) const {
    out[0] = 100.0 * (1.0 + 30.0 * u[0] * u[0]) * u[0];
  }
  void tangent(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::MatRef K, nvib::MatRef C) const {
    K(0, 0) = 100.0 * (1.0 + 90.0 * u[0] * u[0]);
    C(0, 0) = 0.0;
  }
  bool uses_velocity() const { return false; }
  bool uses_time() const { return false; }
};

}  // namespace nvib_test
