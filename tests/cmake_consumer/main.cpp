// Integrates x'' + 4 x = 0 with CEMDTS through the installed headers and
// prints the error at t = 1 against cos(2 t).
#include <nvib/nvib.hpp>

#include <cmath>
#include <cstdio>

int main() {
  nvib::Matrix K(1, 1);
  K << 4.0;
  auto model = nvib::make_linear_model(nvib::Mass::diagonal(nvib::Vector::Ones(1)), K);
  nvib::Vector u0 = nvib::Vector::Ones(1), v0 = nvib::Vector::Zero(1);
  const nvib::Result r = nvib::solve(model, nvib::CEMDTS(0.45), 1e-3, 1.0, u0, v0);
  const double err = std::abs(r.u(r.t.size() - 1, 0) - std::cos(2.0));
  std::printf("nvib consumer: steps %lld, error %.3e\n", static_cast<long long>(r.stats.num_steps), err);
  return err < 1e-5 ? 0 : 1;
}
