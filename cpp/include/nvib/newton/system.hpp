// The linear system of the Newton component: the iteration matrix assembled
// from the model (iteration_matrix.hpp) and factorised (linalg/): dense, banded
// or sparse, chosen once per stepper by its pattern and size (or forced) and
// named in Stats::linear_solver. The Newton component asks it for
//   bool factorize(model, IterationMatrix, Stats&, bool finite_difference, choice)   false if S is singular
//   void solve_in_place(Vector& x)                      x <- S^{-1} x
//   void multiply_C(const Vector& x, Vector& out) const out = C_t x (the last tangent)
//   Vector tangent_diagonal()                           the diagonal of the last K_t
//   Index first_nonfinite_tangent_row() const           -1 if the last tangent is finite
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "../base/types.hpp"
#include "../linalg/banded_ldlt.hpp"
#include "../linalg/dense_lu.hpp"
#include "../linalg/sparse_factorization.hpp"
#include "../model/mass.hpp"
#include "iteration_matrix.hpp"
#include "low_rank.hpp"
#include "options.hpp"

namespace nvib {

// Every name Stats::linear_solver takes (a pickled or saved name is read back through this list).
inline constexpr const char* kLinearSolverNames[] = {
    "dense LU",  "banded LDLT", "sparse LDLT", "supernodal LDLT", "sparse LU", "sparse LDLT + low-rank update",
    "supernodal LDLT + low-rank update", "sparse LU + low-rank update"};

class IterationSystem {
 public:
  // Automatic choice: a symmetric S whose band (half-width b <= n/2, natural order) holds at most
  // twice the entries of its lower triangle is factorised in the band (a chain, a shear building, a
  // beam: no fill outside it, and no index lists); otherwise up to kDenseBelow DOFs the dense LU (faster
  // there than a sparse factorisation), up to kDenseFullMax also when S is more than a quarter full,
  // else sparse LDL^T or LU; and where that sparse S is a large linear part with a few nonlinear DOFs
  // (at most LowRankUpdate::kAutoMaxRank, and at most one DOF in kLowRankMinRatio), the linear part
  // factorised once and the effects' tangent applied as a low-rank update (low_rank.hpp).
  static constexpr Index kDenseBelow = 64, kDenseFullMax = 500, kLowRankMinRatio = 16;
  static constexpr const char* kDenseName = "dense LU";
  static constexpr const char* kBandedName = "banded LDLT";

  void resize(Index) { chosen_ = false; }
  const char* name() const {
    if (!chosen_) return "";
    if (kind_ == Kind::dense) return kDenseName;
    if (kind_ == Kind::banded && !band_failed_) return kBandedName;
    if (kind_ == Kind::low_rank) return low_rank_.name();
    return sparse_lu_.name();
  }
  bool is_dense() const { return kind_ == Kind::dense; }

  // Assembles S and factorises it, unless it is, bit for bit, the S factorised last (a piecewise-linear
  // law on the same branch): then the factors are kept and reused() says so.
  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference,
                 LinearSolverChoice choice = LinearSolverChoice::automatic) {
    if (!chosen_) choose(model, finite_difference, choice);
    reused_ = false;
    if (kind_ == Kind::dense) {
      if (dense_S_.size() != model.size() || S_.rows() != model.size()) {
        dense_S_.resize(model.size());
        lu_.resize(model.size());
        S_.setZero(model.size(), model.size());
        have_last_ = false;
      }
      st.linear_solver = kDenseName;
      dense_S_.assemble(model, im, st, finite_difference, S_);
      if (have_last_ && same_values(S_.data(), last_.data(), S_.size())) return reused_ = true, last_ok_;
      lu_.assembly() = S_;
      last_ok_ = lu_.factorize_assembled();
      last_ = S_;
      have_last_ = true;
      return last_ok_;
    }
    if (kind_ == Kind::low_rank) {
      if (low_rank_.base(model, im)) return factorize_low_rank(model, im, st);
      setup_sparse(model);  // S0 is singular (a static problem, say): S itself is factorised from now on
      have_last_ = false;   // (what was kept is the low-rank update's, not a factorised S)
    }
    if (!sparse_S_.assemble(model, im, st)) return have_last_ = false;
    const double* values = sparse_S_.values();
    const Index count = sparse_S_.num_read();  // (the places the factorisation reads)
    st.linear_solver = name();
    if (have_last_ && same_values(values, last_.data(), count)) return reused_ = true, last_ok_;
    if (kind_ == Kind::banded) {
      // A pivot the band cannot take without pivoting: this S goes to the sparse LU (with pivoting).
      const bool failed_before = band_failed_;
      band_failed_ = !banded_.factorize(values);
      last_ok_ = !band_failed_;
      if (band_failed_) {
        SparseMatrix& S = sparse_S_.matrix();
        banded_.to_compressed(values, S);
        if (!lu_ready_) sparse_lu_.analyze(S, false);
        lu_ready_ = true;
        last_ok_ = sparse_lu_.factorize(S);
      }
      if (band_failed_ || failed_before) st.linear_solver = name();  // (the name above was the band's)
    } else {
      last_ok_ = sparse_lu_.factorize(sparse_S_.matrix());
      st.linear_solver = name();  // (the sparse LU's name says which factorisation it took)
    }
    last_.resize(count, 1);
    std::copy(values, values + count, last_.data());
    have_last_ = true;
    return last_ok_;
  }
  // The last factorize() kept the factors of an identical S.
  bool reused() const { return reused_; }
  void solve_in_place(Vector& x) const {
    if (kind_ == Kind::dense)
      lu_.solve_in_place(x);
    else if (kind_ == Kind::low_rank)
      low_rank_.solve_in_place(x);
    else if (kind_ == Kind::banded && !band_failed_)
      banded_.solve_in_place(x.data());
    else
      sparse_lu_.solve_in_place(x);
  }
  void multiply_C(const Vector& x, Vector& out) const {
    if (kind_ == Kind::dense)
      dense_S_.multiply_C(x, out);
    else
      sparse_S_.multiply_C(x, out);
  }
  Vector tangent_diagonal() { return is_dense() ? dense_S_.tangent_diagonal() : sparse_S_.tangent_diagonal(); }
  Index first_nonfinite_tangent_row() const {
    return is_dense() ? dense_S_.first_nonfinite_tangent_row() : sparse_S_.first_nonfinite_tangent_row();
  }

 private:
  // The effects' tangent alone (S's linear part keeps its factors): reused when A is the last one.
  template <class ModelT>
  bool factorize_low_rank(ModelT& model, const IterationMatrix& im, Stats& st) {
    const bool finite = sparse_S_.assemble_tangent(model, im, st);
    st.linear_solver = name();
    if (!finite) return have_last_ = false;
    low_rank_.fill(sparse_S_.k_values(), sparse_S_.c_values(), im);
    if (have_last_ && low_rank_.same_as_last()) return reused_ = true, last_ok_;
    last_ok_ = low_rank_.factorize_filled();
    have_last_ = true;
    return last_ok_;
  }
  template <class ModelT>
  void choose(const ModelT& model, bool finite_difference, LinearSolverChoice choice) {
    const Index n = model.size();
    chosen_ = true;
    have_last_ = band_failed_ = lu_ready_ = false;
    const bool sparse_possible = model.has_sparse_tangent() && !finite_difference;
    const std::string asked = std::string("'") + to_string(choice) + "'";
    NVIB_CHECK(choice == LinearSolverChoice::automatic || choice == LinearSolverChoice::dense || sparse_possible,
               "linear_solver",
               finite_difference ? asked + " needs jacobian='analytic' (a finite-difference tangent is dense)"
                                 : asked + " needs a model whose tangent is known entry by entry (declared effects "
                                           "and laws on measures; not a force callable)");
    if (!sparse_possible || choice == LinearSolverChoice::dense) {
      const double mb = 16.0 * static_cast<double>(n) * static_cast<double>(n) / 1e6;
      // the argument to blame: the dense solver the caller asked for on a model whose tangent is sparse,
      // the finite-difference tangent, or the model whose force gives only a dense tangent
      const bool asked = sparse_possible && choice == LinearSolverChoice::dense;
      NVIB_CHECK(n <= Mass::kDenseMax, asked ? "linear_solver" : finite_difference ? "jacobian" : "model",
                 asked ? "'dense' factorises the iteration matrix as a dense " + std::to_string(n) + " x " +
                             std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                             std::to_string(Mass::kDenseMax) +
                             " DOFs use linear_solver='sparse' (or 'auto', the default: this model's tangent is sparse)"
                 : finite_difference
                     ? "a finite-difference tangent differentiates the whole force, a dense " + std::to_string(n) +
                           " x " + std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                           std::to_string(Mass::kDenseMax) + " DOFs use jacobian='analytic'"
                     : "the force of this model gives its tangent only as a dense " + std::to_string(n) + " x " +
                           std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                           std::to_string(Mass::kDenseMax) +
                           " DOFs declare its forces as effects (their tangent is sparse), or use an explicit scheme");
      kind_ = Kind::dense;
    } else if (choice == LinearSolverChoice::sparse) {
      setup_sparse(model);
    } else {
      sparse_S_.setup(model);
      const SparseMatrix& S = sparse_S_.matrix();
      const Index b = BandedLDLT::half_bandwidth(S);
      const bool band_fits = sparse_S_.symmetric() && 2 * b <= n && (b + 1) * n <= 2 * lower_nonzeros(S);
      NVIB_CHECK(choice != LinearSolverChoice::banded || sparse_S_.symmetric(), "linear_solver",
                 "'banded' factorises a symmetric iteration matrix (LDL^T); this model's K or C is not symmetric: "
                 "use 'sparse' (LU) or 'auto'");
      if (choice == LinearSolverChoice::banded || (band_fits && choice != LinearSolverChoice::low_rank)) {
        kind_ = Kind::banded;
        banded_.analyze(S);
        sparse_S_.retarget(banded_.layout(S), banded_.size());
      } else if (n <= kDenseBelow && choice != LinearSolverChoice::low_rank) {
        kind_ = Kind::dense;
      } else if (choose_low_rank(model, choice)) {
        kind_ = Kind::low_rank;
      } else {
        sparse_lu_.analyze(S, sparse_S_.symmetric());
        lu_ready_ = true;
        const double fill = static_cast<double>(sparse_S_.nonzeros()) / (static_cast<double>(n) * static_cast<double>(n));
        kind_ = n <= kDenseFullMax && fill > 0.25 ? Kind::dense : Kind::sparse;
      }
    }
    if (kind_ == Kind::dense) {
      dense_S_.resize(n);
      lu_.resize(n);
    }
  }
  // The low-rank update where it was asked for, or (automatic) where the nonlinear tangent touches at
  // most kAutoMaxRank DOFs and at most one in kLowRankMinRatio.
  template <class ModelT>
  bool choose_low_rank(const ModelT& model, LinearSolverChoice choice) {
    const Index n = model.size();
    const Index p = static_cast<Index>(LowRankUpdate::touched_dofs(sparse_S_.k_entries(), sparse_S_.c_entries()).size());
    if (choice == LinearSolverChoice::low_rank) {  // (p = 0, no nonlinear tangent: S is the linear part)
      const double mb = 8.0 * static_cast<double>(n) * static_cast<double>(p) / 1e6;
      NVIB_CHECK(mb <= 4096.0, "linear_solver",
                 "'low_rank' keeps an n x p matrix for the " + std::to_string(p) + " DOFs the effects' tangent touches (" +
                     detail::fmt(mb) + " MB); use 'sparse' or 'auto'");
    } else if (!(choice == LinearSolverChoice::automatic && p > 0 && p <= LowRankUpdate::kAutoMaxRank &&
                 kLowRankMinRatio * p <= n)) {
      return false;
    }
    low_rank_.setup(model, sparse_S_.k_entries(), sparse_S_.c_entries(), model.uses_velocity(), sparse_S_.symmetric());
    return true;
  }
  template <class ModelT>
  void setup_sparse(const ModelT& model) {
    sparse_S_.setup(model);
    sparse_lu_.analyze(sparse_S_.matrix(), sparse_S_.symmetric());
    lu_ready_ = true;
    kind_ = Kind::sparse;
  }
  static Index lower_nonzeros(const SparseMatrix& A) {
    Index k = 0;
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) k += it.row() >= j;
    return k;
  }

  enum class Kind { dense, banded, sparse, low_rank };
  Kind kind_ = Kind::dense;
  bool chosen_ = false;
  bool have_last_ = false, last_ok_ = false, reused_ = false;
  bool band_failed_ = false;  // the last S had a pivot the band cannot take: it went to the sparse LU
  bool lu_ready_ = false;     // sparse_lu_ has analysed S's pattern
  Matrix S_, last_;  // the assembled S (dense), and the S of the factors kept (dense, or the sparse values)
  DenseIterationMatrix dense_S_;
  DenseLU lu_;
  SparseIterationMatrix sparse_S_;
  BandedLDLT banded_;
  SparseFactorization sparse_lu_;
  LowRankUpdate low_rank_;
};

}  // namespace nvib
