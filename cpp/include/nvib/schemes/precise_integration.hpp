// Precise integration method (PIM; Zhong & Williams 1994) with a
// Lagrange-interpolation predictor-corrector for the nonlinear force.
//
// State x = [u; v], x' = H x + r(t, x) with H the model's linear part about
// u = v = 0 (constant K, C plus the tangent of the nonlinear force there) and
// r = [0; -M^{-1}(G - K0 u - C0 v)] the nonlinear remainder and the loads.
// Over a step, r(t_n + s) is replaced by its interpolating polynomial
// sum_k c_k (s/h)^k and integrated exactly:
//   x_{n+1} = T x_n + sum_k c_k k! h^{-k} int_0^h e^{H(h-s)} s^k ds,   T = e^{Hh}.
// The moment integrals come from the exponential of the block matrix
// h [[H, I, 0, ..], [0, 0, I, ..], ..] (Van Loan 1978): its first block row is
// [T, h phi_1, h^2 phi_2, ...], and int_0^h e^{H(h-s)} s^k ds = k! h^{k+1} phi_{k+1}.
// The 2^N algorithm squares only that row (expm_increment_with_moments: the
// rows below are known). No H^{-1} is needed, so a singular linear part (a
// free-floating vehicle) is fine. Each pass is one matrix-vector product with
// the propagator folded with the interpolation weights.
//
// interpolation p: polynomial degree of the interpolation (p + 1 points). It is not the order of
// accuracy (order_u below); the parameter was called `order` before, and that name is refused.
// Predictor: extrapolation through r_n, r_{n-1}, ..; corrector: interpolation
// through r(x~_{n+1}), r_n, r_{n-1}, ..; `corrections` corrector passes; the
// history value r_{n+1} is evaluated at the corrected state (P(EC)^k E).
#pragma once

#include <array>

#include <algorithm>
#include <string>
#include <vector>

#include "../linalg/expm.hpp"
#include "scheme.hpp"
#include "stepper.hpp"

namespace nvib {

template <class ModelT>
class PreciseIntegrationStepper;

struct PreciseIntegration {
  static constexpr const char* name = "PreciseIntegration";
  static constexpr const char* key = "pim";
  static constexpr const char* doc =
      "Precise integration method (Zhong & Williams 1994): the exponential of the linear part by the 2^N "
      "algorithm, the nonlinear remainder by a Lagrange predictor-corrector integrated exactly. Dense: its "
      "set-up is O(n^3) in the number of degrees of freedom.";
  static constexpr bool is_explicit = true;
  int squarings = 20;
  int interpolation = 2;
  int corrections = 1;

  explicit PreciseIntegration(int squarings_ = 20, int interpolation_ = 2, int corrections_ = 1)
      : squarings(squarings_), interpolation(interpolation_), corrections(corrections_) {
    validate();
  }

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.squarings, param::integer("squarings", "2^N squarings of the exponential").range(1, 60));
    v(s.interpolation, param::integer("interpolation", "polynomial degree of the interpolation of the remainder "
                                                       "(not the order of accuracy)")
                              .range(1, 3)
                              .renamed_from("order"));
    v(s.corrections, param::integer("corrections", "corrector passes per step").range(0, 10));
  }
  void validate() const { param::check_ranges(*this); }
  std::string label() const {
    std::string parts;
    auto add = [&](const std::string& p) { parts += (parts.empty() ? "" : ", ") + p; };
    if (squarings != 20) add("N=" + std::to_string(squarings));
    if (interpolation != 2) add("interp. " + std::to_string(interpolation));
    if (corrections != 1) add(std::to_string(corrections) + " corr.");
    return parts.empty() ? "PIM" : "PIM(" + parts + ")";
  }
  // Interpolating with degree p gives order p + 1, up to 3: the first step,
  // with a constant predictor and a linear corrector, leaves an O(h^3) error.
  // Without a corrector the first step's constant extrapolation leaves O(h^2).
  int order_u() const { return corrections > 0 ? std::min(interpolation + 1, 3) : 2; }
  int order_v() const { return order_u(); }
  template <class M>
  using stepper = PreciseIntegrationStepper<M>;
};

// What PIM's dense set-up costs for n DOFs: the bytes of its propagators, moments and
// workspace, and its flops (about 2 (q + 1) (2n)^3 per squaring, q = interpolation + 1).
struct PimCost {
  double bytes, flops;
};
inline PimCost pim_cost(Index n, const PreciseIntegration& s) {
  const double N = 2.0 * static_cast<double>(n), q = s.interpolation + 1.0;
  const double propagators = 2.0 * q * N * (N + q * static_cast<double>(n));  // the predictor and corrector propagators
  const double moments = 3.0 * (q + 1.0) * N * N;                            // exponential, moments, temporaries
  return {8.0 * (propagators + moments), 2.0 * (q + 1.0) * N * N * N * (s.squarings + 2.0)};
}
// PIM is dense: above this size it is refused (at n = 1000: about 0.5 GB and 2.5 minutes of set-up
// on a 2026 laptop core; the cost grows as n^3).
constexpr Index kPimMaxDofs = 1000;

namespace detail {
// Maps values at nodes sigma_j to monomial coefficients: c = L * values.
inline Matrix lagrange_to_monomial(const std::vector<double>& nodes) {
  const Index m = static_cast<Index>(nodes.size());
  Matrix V(m, m);
  for (Index j = 0; j < m; ++j)
    for (Index k = 0; k < m; ++k) V(j, k) = std::pow(nodes[static_cast<size_t>(j)], static_cast<double>(k));
  return V.fullPivLu().inverse();
}
}  // namespace detail

template <class ModelT>
class PreciseIntegrationStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;
  NVIB_STEPPER_STATE(Base);

 public:
  PreciseIntegrationStepper(const PreciseIntegration& scheme, ModelT model, double h)
      : Base(std::move(model), h), p_(scheme) {
    const Index n = this->size(), N = 2 * n, q = p_.interpolation + 1;
    if (n > kPimMaxDofs) {
      const PimCost c = pim_cost(n, p_);
      detail::throw_argument(
          "scheme", "PreciseIntegration is dense: for " + std::to_string(n) + " DOFs its set-up would need about " +
                        detail::fmt(c.bytes / 1e9) + " GB and " + detail::fmt(c.flops / 5e9 / 60.0) +
                        " minutes (at 5 GFLOP/s), growing as n^3; its limit is " + std::to_string(kPimMaxDofs) +
                        " DOFs. Use an explicit scheme (CentralDifference, CEMDTS, Zhai) or an implicit one "
                        "(Newmark, GeneralizedAlpha): they are sparse");
    }
    x_.setZero(N);
    z_.setZero(N + n * q);
    rnew_.setZero(n);
    R_.setZero(n, q);
    // Interpolation matrices, transposed so that Cc = R * Lt; zero-padded to q columns.
    for (Index m = 1; m <= q; ++m) {
      std::vector<double> pred, corr;
      for (Index j = 0; j < m; ++j) pred.push_back(-static_cast<double>(j));
      corr.push_back(1.0);
      for (Index j = 0; j + 1 < m; ++j) corr.push_back(-static_cast<double>(j));
      Matrix Lp = Matrix::Zero(q, q), Lc = Matrix::Zero(q, q);
      Lp.topLeftCorner(m, m) = detail::lagrange_to_monomial(pred).transpose();
      Lc.topLeftCorner(m, m) = detail::lagrange_to_monomial(corr).transpose();
      Lpred_.push_back(Lp);
      Lcorr_.push_back(Lc);
    }
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    if (!ready_) build_propagators(t0);
    x_.head(this->size()) = u_;
    x_.tail(this->size()) = v_;
    remainder(a_, R_.col(0));
    nhist_ = 1;
  }

  Status step() {
    const double t1 = this->next_time();
    const Index n = this->size(), N = 2 * n, q = p_.interpolation + 1;
    // z = [x_n; r_n; r_{n-1}; ..]: R_ is column-major, so its columns are the stacked history.
    z_.head(N) = x_;
    z_.tail(n * q) = Eigen::Map<const Vector>(R_.data(), n * q);
    // Predictor: extrapolate the history.
    const Index mp = std::min<Index>(q, nhist_);
    x_.noalias() = cache_[active_].pred[static_cast<size_t>(mp - 1)] * z_;
    for (int c = 0; c < p_.corrections; ++c) {
      evaluate(t1);
      // Corrector: interpolate through r(x~_{n+1}) and the history: z = [x_n; r~_{n+1}; r_n; ..].
      const Index mc = std::min<Index>(q, nhist_ + 1);
      z_.segment(N, n) = rnew_;
      if (q > 1) z_.tail(n * (q - 1)) = Eigen::Map<const Vector>(R_.data(), n * (q - 1));
      x_.noalias() = cache_[active_].corr[static_cast<size_t>(mc - 1)] * z_;
    }
    // The first steps' corrector used r at a predicted state of a lower order: its error is accounted
    // for (account_startup) with the final r.
    const bool startup = track_ && p_.corrections > 0 && nhist_ < q;
    if (startup) r_tilde_ = rnew_;
    evaluate(t1);
    if (startup) account_startup(std::min<Index>(q, nhist_ + 1));
    if (track_) account_error(p_.corrections > 0 ? std::min<Index>(q, nhist_ + 1) : std::min<Index>(q, nhist_));
    // Shift the history (newest first).
    for (Index j = q - 1; j > 0; --j) R_.col(j) = R_.col(j - 1);
    R_.col(0) = rnew_;
    nhist_ = std::min<Index>(q, nhist_ + 1);
    return this->advance();
  }

  // The run's own error estimate (error_estimate.hpp, "The precise integration method"): on, the
  // stepper follows e = x - x_exact, the local error of each step's interpolation of the remainder
  // propagated by the exponential; error_u() is its displacement half, updated every kErrorBlock steps
  // (error_updates() counts the updates). Off by default; switching it on starts e at 0.
  static constexpr int kErrorBlock = 8;
  void track_error(bool on) {
    track_ = on;
    if (!on) return;
    const Index n = this->size();
    // C(m) (-1)^i binom(m, i): the weights of the newest m + 1 remainders in C(m) D^m r.
    for (Index m = 1; m <= p_.interpolation + 1; ++m) {
      auto& w = difference_weights_[static_cast<size_t>(m - 1)];
      const double c = error_constant_of(m, p_.corrections > 0);
      double binom = 1.0;
      for (Index i = 0; i <= m; ++i) {
        w[static_cast<size_t>(i)] = (i % 2 == 0 ? c : -c) * binom;
        binom = binom * static_cast<double>(m - i) / static_cast<double>(i + 1);
      }
    }
    err_.setZero(2 * n);
    r_tilde_.setZero(n);
    dsum_.setZero(n);
    dabs_.setZero(n);
    dtmp_.setZero(n);
    pending_ = 0;
    block_ = 0;
    updates_ = 0;
  }
  auto error_u() const { return err_.head(this->size()); }
  std::int64_t error_updates() const { return updates_; }
  // The steps of a block not yet propagated, added where they are (at the end of a run).
  void flush_error() {
    if (!track_ || block_ == 0) return;
    const Index n = this->size(), N = 2 * n;
    block_mean();
    err_.noalias() += static_cast<double>(block_) * cache_[active_].pred[0].block(0, N, N, n) * dtmp_;
    end_block();
  }

  const PreciseIntegration& scheme() const { return p_; }

  // State: [u; v; a; r_n, r_{n-1}, ..] with the order + 1 remainders of the
  // interpolation history (newest first, n entries each). set_state() marks
  // the whole history as known.
  Index state_size() const { return this->size_with(R_.size()); }
  Vector state() const { return this->state_with(Eigen::Map<const Vector>(R_.data(), R_.size())); }
  void set_state(double t, const Vector& x) {
    NVIB_CHECK(ready_, "set_state", "initialize() must come first (it builds the exponential)");
    Eigen::Map<Vector> history(R_.data(), R_.size());
    this->set_state_with(t, x, history);
    const Index n = this->size();
    x_.head(n) = u_;
    x_.tail(n) = v_;
    nhist_ = R_.cols();
    pending_ = 0;
  }
  const Matrix& transition() const { return cache_[active_].T; }


  // Variable steps: the remainders of the history, known at t_n, t_n - h, t_n - 2h, .., are moved to the
  // nodes of the new step h' by the polynomial through them (the interpolation the scheme itself
  // makes), and the propagators of h' come from a cache of the last few step lengths (an exponential
  // each: a step length used before costs nothing).
  void set_dt(double h) {
    if (h == h_) return;
    const Index m = nhist_;
    if (m > 1) {
      const double r = h / h_;
      Matrix moved = Matrix::Zero(R_.rows(), R_.cols());
      moved.col(0) = R_.col(0);
      for (Index k = 1; k < m; ++k) {
        const double y = -static_cast<double>(k) * r;
        for (Index j = 0; j < m; ++j) {
          double w = 1.0;
          for (Index l = 0; l < m; ++l)
            if (l != j) w *= (y + static_cast<double>(l)) / (static_cast<double>(l) - static_cast<double>(j));
          moved.col(k) += w * R_.col(j);
        }
      }
      R_ = moved;
    }
    Base::set_dt(h);
    use_propagators();
  }
  void checkpoint(int slot = 0) {
    Base::checkpoint(slot);
    ck_R_[static_cast<size_t>(slot)] = R_;
    ck_nhist_[static_cast<size_t>(slot)] = nhist_;
  }
  void rollback(int slot = 0) {
    const double h = h_;
    Base::rollback(slot);
    R_ = ck_R_[static_cast<size_t>(slot)];
    nhist_ = ck_nhist_[static_cast<size_t>(slot)];
    pending_ = 0;
    x_.head(this->size()) = u_;
    x_.tail(this->size()) = v_;
    if (h_ != h) use_propagators();
  }

 private:
  // The propagators of a step length: T = e^{hH} and the predictor and corrector matrices (T folded with
  // the interpolation weights, see make_propagators), one per number of known points.
  struct Propagators {
    double h = 0.0;
    Matrix T;
    std::vector<Matrix> pred, corr;
    Matrix Tb, S;  // with the error estimate: T^kErrorBlock and sum_{j < kErrorBlock} T^j W0
  };
  // T = e^{hH} and the moment integrals W_k = k! h^{-k} int_0^h e^{H(h-s)} s^k ds
  // (velocity columns: r has a zero top half), folded with the interpolation
  // weights into one matrix per predictor and corrector variant:
  //   x_{n+1} = T x_n + sum_k W_k c_k,  c = R L  =>  x_{n+1} = [T | W'_0 | W'_1 | ..] [x_n; r_0; r_1; ..]
  // with W'_j = sum_k L(j, k) W_k: one matrix-vector product per pass.
  void build_propagators(double t0) {
    const Index n = this->size(), N = 2 * n;
    Matrix K0(n, n), C0(n, n);
    Vector zero = Vector::Zero(n);
    model_.tangent(zero, zero, t0, K0, C0, stats_);
    Matrix H = Matrix::Zero(N, N);
    H.topRightCorner(n, n).setIdentity();
    Matrix MK = K0, MC = C0;
    for (Index j = 0; j < n; ++j) {
      auto ck = MK.col(j);
      auto cc = MC.col(j);
      model_.mass().solve_in_place(ck);
      model_.mass().solve_in_place(cc);
    }
    H.bottomLeftCorner(n, n) = -MK;
    H.bottomRightCorner(n, n) = -MC;
    Hlo_ = H.bottomRows(n);
    H_ = H;
    cache_.clear();
    use_propagators();
    ready_ = true;
  }

  // The propagators of the step h_: from the cache of the last kCached step lengths, else built.
  void use_propagators() {
    for (std::size_t k = 0; k < cache_.size(); ++k)
      if (cache_[k].h == h_) {
        active_ = k;
        return;
      }
    if (cache_.size() >= kCached) cache_.erase(cache_.begin());
    cache_.push_back(make_propagators(h_));
    active_ = cache_.size() - 1;
  }

  Propagators make_propagators(double h) {
    const Index n = this->size(), N = 2 * n, q = p_.interpolation + 1;
    Propagators out;
    out.h = h;
    // First block row of the exponential of h [[H, I, 0, ..], [0, 0, I, ..], ..] (Van Loan 1978).
    std::vector<Matrix> F;
    Matrix T = expm_increment_with_moments(h * H_, h, static_cast<int>(q), F, p_.squarings);
    T.diagonal().array() += 1.0;
    ++stats_.num_expm;
    std::vector<Matrix> W;
    double fact = 1.0;
    for (Index k = 0; k < q; ++k) {
      if (k > 0) fact *= static_cast<double>(k);
      W.push_back(fact / std::pow(h, static_cast<double>(k)) * F[static_cast<size_t>(k)].rightCols(n));
    }
    auto fold = [&](const Matrix& L) {
      Matrix P = Matrix::Zero(N, N + n * q);
      P.leftCols(N) = T;
      for (Index j = 0; j < q; ++j)
        for (Index k = 0; k < q; ++k)
          if (L(j, k) != 0.0) P.block(0, N + j * n, N, n) += L(j, k) * W[static_cast<size_t>(k)];
      return P;
    };
    for (Index m = 0; m < q; ++m) {
      out.pred.push_back(fold(Lpred_[static_cast<size_t>(m)]));
      out.corr.push_back(fold(Lcorr_[static_cast<size_t>(m)]));
    }
    out.T = std::move(T);
    return out;
  }

  // The local error of the step just taken, whose interpolation used `used` points: r - p, the remainder
  // minus its interpolating polynomial, is r^(m) h^m / m! prod (s/h - node) to leading order, and its
  // integral against e^{H(h-s)} is about W0 C(m) D^m r, W0 = int_0^h e^{H(h-s)} ds [0; I] and D^m r
  // the m-th backward difference of the remainders (C(m): error_constant_of below). A step whose
  // difference needs a remainder not yet known (the first steps) is accounted one step later.
  void account_error(Index used) {
    const Index known = nhist_ + 1;  // before the shift: R_'s nhist_ remainders and rnew_
    if (pending_ > 0 && pending_ + 1 <= known) {
      add_difference(pending_);
      pending_ = 0;
    }
    if (used + 1 <= known) {
      add_difference(used);
    } else {
      pending_ = used;
    }
    if (++block_ < kErrorBlock) return;
    // A block of steps: e <- T^b e + sum_j T^(b-1-j) W0 d_j, with the d_j of the block replaced by their
    // mean (S = sum_j T^j W0, built once per step length).
    Propagators& P = cache_[active_];
    if (P.Tb.size() == 0) error_propagators(P);
    block_mean();
    err_ = P.Tb * err_;
    err_.noalias() += P.S * dtmp_;
    end_block();
  }
  void end_block() {
    dsum_.setZero();
    dabs_.setZero();
    block_ = 0;
    ++updates_;
  }
  // The block's local errors as one mean (into dtmp_): their sum's sign, the sum of their sizes. Near a
  // kink of r (a yield point, a contact, a record's sample) the differences D^m r of successive steps
  // alternate and their sum telescopes, while the errors they stand for do not cancel; where r is smooth
  // the two sums agree.
  void block_mean() {
    const double inv = 1.0 / static_cast<double>(block_);
    for (Index i = 0; i < dtmp_.size(); ++i) dtmp_[i] = (dsum_[i] < 0.0 ? -dabs_[i] : dabs_[i]) * inv;
  }
  // A step whose predictor had fewer points than its corrector (the first steps): the corrector's r at
  // the new time was r~, at a state of the predictor's lower order, where the answer's r is rnew_; the
  // answer is off by the corrector's weight of that point times their difference.
  void account_startup(Index mc) {
    const Index n = this->size(), N = 2 * n;
    dtmp_ = r_tilde_ - rnew_;
    err_.noalias() += cache_[active_].corr[static_cast<size_t>(mc - 1)].block(0, N, N, n) * dtmp_;
  }
  // dsum_ -= C(m) D^m r and dabs_ += |C(m) D^m r|, D^m r over the newest m + 1 remainders (rnew_, then
  // R_'s columns, before the history shifts): one pass over them.
  void add_difference(Index m) {
    const Index n = this->size();
    std::array<const double*, kMaxPoints + 1> col{};
    for (Index i = 0; i <= m; ++i) col[static_cast<size_t>(i)] = i == 0 ? rnew_.data() : R_.col(i - 1).data();
    const std::array<double, kMaxPoints + 1>& w = difference_weights_[static_cast<size_t>(m - 1)];
    double *sum = dsum_.data(), *abs = dabs_.data();
    for (Index k = 0; k < n; ++k) {
      double d = 0.0;
      for (Index i = 0; i <= m; ++i) d += w[static_cast<size_t>(i)] * col[static_cast<size_t>(i)][k];
      sum[k] -= d;
      abs[k] += std::abs(d);
    }
  }
  // C(m) = int_0^1 prod_k (s - node_k) ds / m!, the nodes of the interpolation with m points: 1, 0, -1,
  // .. for the corrector, 0, -1, .. for the predictor (m = 3: -1/24 and 3/8, Adams' constants).
  static double error_constant_of(Index m, bool corrector) {
    std::vector<double> poly{1.0};  // coefficients of prod (s - node), lowest degree first
    for (Index k = 0; k < m; ++k) {
      const double node = corrector ? 1.0 - static_cast<double>(k) : -static_cast<double>(k);
      std::vector<double> next(poly.size() + 1, 0.0);
      for (std::size_t i = 0; i < poly.size(); ++i) {
        next[i + 1] += poly[i];
        next[i] -= node * poly[i];
      }
      poly = std::move(next);
    }
    double integral = 0.0, fact = 1.0;
    for (std::size_t i = 0; i < poly.size(); ++i) integral += poly[i] / static_cast<double>(i + 1);
    for (Index k = 2; k <= m; ++k) fact *= static_cast<double>(k);
    return integral / fact;
  }
  void error_propagators(Propagators& P) {
    const Index n = this->size(), N = 2 * n;
    const auto W0 = P.pred[0].block(0, N, N, n);
    P.S = W0;
    Matrix power = P.T;
    for (int j = 1; j < kErrorBlock; ++j) {
      P.S.noalias() += power * W0;
      if (j + 1 < kErrorBlock) power = power * P.T;
    }
    P.Tb = power * P.T;
  }

  // Evaluates the force at x_ (time t1): sets u_, v_, a_ and the remainder rnew_.
  void evaluate(double t1) {
    const Index n = this->size();
    u_ = x_.head(n);
    v_ = x_.tail(n);
    model_.acceleration(u_, v_, t1, a_, stats_);
    remainder(a_, rnew_);
  }

  // r = a - Hlo x  (= -M^{-1} (G - K0 u - C0 v))
  template <class Out>
  void remainder(const Vector& a, Out&& out) {
    out = a;
    out.noalias() -= Hlo_ * x_;
  }

  PreciseIntegration p_;
  bool ready_ = false;
  Matrix H_, Hlo_;
  std::vector<Matrix> Lpred_, Lcorr_;  // interpolation weights per number of known points
  static constexpr std::size_t kCached = 4;
  std::vector<Propagators> cache_;
  std::size_t active_ = 0;
  Vector x_, z_, rnew_;
  Matrix R_;
  std::array<Matrix, Base::kCheckpoints> ck_R_;
  Index nhist_ = 0;
  std::array<Index, Base::kCheckpoints> ck_nhist_{};
  // The error estimate (track_error): e, the block's sum of -C(m) D^m r and of its sizes, r~ of the first
  // steps.
  bool track_ = false;
  Vector err_, dsum_, dabs_, dtmp_, r_tilde_;
  static constexpr std::size_t kMaxPoints = 4;  // interpolation + 1 <= 4
  std::array<std::array<double, kMaxPoints + 1>, kMaxPoints> difference_weights_{};
  Index pending_ = 0;  // a first step's difference order, accounted one step later
  int block_ = 0;
  std::int64_t updates_ = 0;
};

}  // namespace nvib
