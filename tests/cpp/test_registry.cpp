// Typed checks over every scheme of the registry (schemes/all.hpp): each has
// a unique key, a name and a label, valid defaults, parameters with unique
// names, and the global orders it declares, fitted by self-convergence on the
// hardening oscillator (no closed form needed: successive differences of the
// end state shrink by 2^p per halving of the step).
#include <nvib/nvib.hpp>

#include <cmath>
#include <set>
#include <string>

#include "check.hpp"
#include "models.hpp"

using nvib::Vector;

namespace {

using nvib_test::Hardening;

// Slope of log |state(h) - state(h/2)| against log h over the halvings of h0.
template <class Scheme>
void fitted_orders(const Scheme& s, double& pu, double& pv) {
  const auto model = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(1)), Hardening{});
  // Started off a turning point: from rest the problem is symmetric in time about t = 0, and some
  // schemes' errors then cancel to a higher order than they have in general.
  const Vector u0 = Vector::Constant(1, 1.5), v0 = Vector::Constant(1, 30.0);
  // t_end a multiple of every step, so each run ends at the same time.
  const double omega = std::sqrt(100.0 * (1.0 + 30.0 * 1.5 * 1.5)), h0 = 0.05 / omega, t_end = 256 * h0;
  double x[6], v[6];
  for (int k = 0; k < 6; ++k) {
    const auto r = nvib::solve(model, s, h0 / std::pow(2.0, k), t_end, u0, v0);
    x[k] = r.u(r.u.rows() - 1, 0);
    v[k] = r.v(r.v.rows() - 1, 0);
  }
  auto slope = [](const double* y) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const int m = 5;
    for (int k = 0; k < m; ++k) {
      const double lx = -k * std::log(2.0), ly = std::log(std::abs(y[k] - y[k + 1]));
      sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    }
    return (m * sxy - sx * sy) / (m * sxx - sx * sx);
  };
  pu = slope(x);
  pv = slope(v);
}

struct NameCollector {
  std::set<std::string> names;
  bool unique = true;
  template <class T, class P>
  void operator()(const T&, const P& p) {
    unique = unique && names.insert(p.name).second;
  }
};

}  // namespace

int main() {
  std::set<std::string> keys, names;
  int count = 0;
  nvib::AllSchemes::for_each([&](auto* tag) {
    using S = std::remove_pointer_t<decltype(tag)>;
    ++count;
    const S s{};
    CHECK(std::string(S::key).size() > 0 && keys.insert(S::key).second);
    CHECK(std::string(S::name).size() > 0 && names.insert(S::name).second);
    CHECK(std::string(S::doc).size() > 20);
    CHECK(!s.label().empty());
    CHECK(nvib::scheme_repr(s).rfind(std::string(S::name) + "(", 0) == 0);
    s.validate();
    NameCollector params;
    S::parameters(s, params);
    CHECK(params.unique);
    CHECK(nvib::has_newton<S>::value == !S::is_explicit);
    double pu = 0, pv = 0;
    fitted_orders(s, pu, pv);
    std::printf("%-20s declared u %d v %d, fitted u %.3f v %.3f\n", S::name, s.order_u(), s.order_v(), pu, pv);
    // Measured: u 2.000 for every second-order scheme, v 1.986 (Zhai) to 2.000; PIM u 2.994, v 3.001.
    CHECK_CLOSE(pu, s.order_u(), 0.1);
    CHECK_CLOSE(pv, s.order_v(), 0.1);
  });
  CHECK(count == static_cast<int>(nvib::AllSchemes::size));
  return nvib_test::finish("test_registry");
}
