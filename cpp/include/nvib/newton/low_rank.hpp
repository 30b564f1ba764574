// The iteration matrix of a large linear model carrying a few nonlinear effects, solved as a
// low-rank update of its linear part (the Sherman-Morrison-Woodbury identity; Golub & Van Loan,
// Matrix Computations, 4th ed., section 2.1.4):
//
//   S = S0 + E A E^T,   S0 = cM M + cC C + cK K   (the linear parts: factorised once per step size)
//                       E  = the p columns of the identity at the DOFs the effects' tangent touches
//                       A  = cK K_e + cC C_e on those DOFs (p x p, the effects' tangent)
//   S^{-1} x = y - Z (I + A W)^{-1} A (E^T y),   y = S0^{-1} x,  Z = S0^{-1} E (n x p),  W = E^T Z.
//
// A Newton iteration then costs one solve with S0's factors, a p x p factorisation and n p
// multiply-adds, instead of a factorisation of S: on a 3-D solid of 10^4 DOFs with a few springs,
// a few milliseconds instead of a second. Z is computed with p solves whenever (cM, cC, cK) change.
// The update is exact in exact arithmetic; in floating point it solves S to the accuracy of S0's
// factors times the conditioning of I + A W, which is that of S relative to S0 (the Newton
// iteration's residual test, not the solve, decides convergence).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "../base/types.hpp"
#include "../linalg/dense_lu.hpp"
#include "../linalg/sparse_factorization.hpp"
#include "iteration_matrix.hpp"

namespace nvib {

class LowRankUpdate {
 public:
  // Above this rank the automatic choice factorises S (IterationSystem); n p doubles of Z and p^3
  // per iteration stay small against a sparse factorisation only for a few nonlinear DOFs.
  static constexpr Index kAutoMaxRank = 64;

  // The DOFs the nonlinear tangent's entries touch (rows and columns), ascending.
  static std::vector<int> touched_dofs(const std::vector<Entry>& K, const std::vector<Entry>& C) {
    std::vector<int> dofs;
    dofs.reserve(2 * (K.size() + C.size()));
    for (const Entry& e : K) dofs.push_back(e.row), dofs.push_back(e.col);
    for (const Entry& e : C) dofs.push_back(e.row), dofs.push_back(e.col);
    std::sort(dofs.begin(), dofs.end());
    dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
    return dofs;
  }

  // The pattern of S0 (mass, K, and C where the model uses velocity) and where the tangent's entries go
  // in A. `symmetric`: S0 is factorised by LDL^T (else LU).
  template <class ModelT>
  void setup(const ModelT& model, const std::vector<Entry>& K, const std::vector<Entry>& C, bool velocity,
             bool symmetric) {
    n_ = model.size();
    velocity_ = velocity;
    symmetric_ = symmetric;
    dofs_ = touched_dofs(K, C);
    p_ = static_cast<Index>(dofs_.size());
    std::vector<int> local(static_cast<size_t>(n_), -1);
    for (Index a = 0; a < p_; ++a) local[static_cast<size_t>(dofs_[static_cast<size_t>(a)])] = static_cast<int>(a);
    auto place = [&](const std::vector<Entry>& entries, std::vector<int>& pos) {
      pos.clear();
      pos.reserve(entries.size());
      for (const Entry& e : entries)
        pos.push_back(local[static_cast<size_t>(e.row)] + static_cast<int>(p_) * local[static_cast<size_t>(e.col)]);
    };
    place(K, posK_);
    place(C, posC_);
    A_.setZero(p_, p_);
    last_A_.setZero(p_, p_);
    W_.setZero(p_, p_);
    Z_.resize(0, 0);
    s_.setZero(p_);
    r_.setZero(p_);
    if (p_ > 0) cap_.resize(p_);
    have_base_ = analyzed_ = have_A_ = false;
  }
  Index rank() const { return p_; }
  Index size() const { return n_; }

  // S0 at (cM, cC, cK) factorised and Z, W computed, unless they are those of the last call; false if
  // S0 is singular (a static problem whose linear stiffness does not hold every DOF: the caller
  // factorises S instead). May allocate (only when the coefficients change).
  template <class ModelT>
  bool base(const ModelT& model, const IterationMatrix& im) {
    if (have_base_ && im.cM == cM_ && im.cC == cC_ && im.cK == cK_) return base_ok_;
    cM_ = im.cM, cC_ = im.cC, cK_ = im.cK;
    have_base_ = true;
    have_A_ = false;
    std::vector<Eigen::Triplet<double, int>> t;
    model.mass().for_each_entry([&](Index i, Index j, double m) { t.emplace_back(int(i), int(j), cM_ * m); });
    add(model.K(), cK_, t);
    if (velocity_) add(model.C(), cC_, t);
    for (Index i = 0; i < n_; ++i) t.emplace_back(int(i), int(i), 0.0);  // the diagonal is in the pattern
    S0_.resize(n_, n_);
    S0_.setFromTriplets(t.begin(), t.end());
    S0_.makeCompressed();
    if (!analyzed_) {
      s0_.analyze(S0_, symmetric_);
      analyzed_ = true;
    }
    base_ok_ = s0_.factorize(S0_);
    if (!base_ok_) return false;
    Z_.setZero(n_, p_);
    Vector e(n_);
    for (Index b = 0; b < p_; ++b) {
      e.setZero();
      e[dofs_[static_cast<size_t>(b)]] = 1.0;
      s0_.solve_in_place(e);
      Z_.col(b) = e;
      for (Index a = 0; a < p_; ++a) W_(a, b) = e[dofs_[static_cast<size_t>(a)]];
    }
    base_ok_ = Z_.allFinite();
    return base_ok_;
  }
  // "supernodal LDLT + low-rank update", ...: the factorisation of S0 and the update.
  const char* name() const { return s0_.name_with_low_rank(); }

  // Whether A is, bit for bit, the A factorised last (its factors can be kept).
  bool same_as_last() const {
    return have_A_ && same_values(A_.data(), last_A_.data(), A_.size());
  }
  // A from the tangent's values (in the order of setup()'s entries), the last one kept to compare
  // (same_as_last) before factorize_filled(). Allocates nothing.
  void fill(const double* kvals, const double* cvals, const IterationMatrix& im) {
    last_A_.swap(A_);
    A_.setZero();
    double* a = A_.data();
    for (size_t k = 0; k < posK_.size(); ++k) a[posK_[k]] += im.cK * kvals[k];
    if (velocity_)
      for (size_t k = 0; k < posC_.size(); ++k) a[posC_[k]] += im.cC * cvals[k];
  }
  // The capacitance I + A W of the filled A factorised; false if it is singular (then so is S).
  bool factorize_filled() {
    have_A_ = true;
    if (p_ == 0) return true;  // no nonlinear DOF: S = S0
    Matrix& cap = cap_.assembly();
    cap.noalias() = A_ * W_;
    cap.diagonal().array() += 1.0;
    return cap_.factorize_assembled();
  }

  // x <- S^{-1} x
  void solve_in_place(Vector& x) const {
    s0_.solve_in_place(x);
    if (p_ == 0) return;
    for (Index a = 0; a < p_; ++a) s_[a] = x[dofs_[static_cast<size_t>(a)]];
    r_.noalias() = A_ * s_;
    cap_.solve_in_place(r_);
    x.noalias() -= Z_ * r_;
  }

 private:
  static void add(const SparseMatrix& A, double c, std::vector<Eigen::Triplet<double, int>>& t) {
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) t.emplace_back(int(it.row()), int(j), c * it.value());
  }

  Index n_ = 0, p_ = 0;
  bool velocity_ = false, symmetric_ = true;
  bool have_base_ = false, base_ok_ = false, analyzed_ = false, have_A_ = false;
  double cM_ = 0.0, cC_ = 0.0, cK_ = 0.0;
  std::vector<int> dofs_, posK_, posC_;
  SparseMatrix S0_;
  SparseFactorization s0_;
  Matrix Z_, W_, A_, last_A_;
  DenseLU cap_;
  mutable Vector s_, r_;
};

}  // namespace nvib
