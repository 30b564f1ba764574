// The iteration matrix of an implicit step, S = cM M + cC C_t + cK K_t with the
// tangents at (u, v, t), assembled from the model: dense (K_t and C_t as n x n
// matrices, for small models and forces whose tangent is only known as a whole
// matrix) or sparse (the force gives its tangent entry by entry). The linear
// algebra that factorises S is in linalg/.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../base/interrupt.hpp"
#include "../base/types.hpp"

namespace nvib {

// Whether a[0 .. n) and b[0 .. n) are the same numbers, bit for bit (signed zeros apart): an iteration
// matrix identical to the one factorised last keeps its factors.
inline bool same_values(const double* a, const double* b, Index n) {
  for (Index k = 0; k < n; ++k)
    if (!(a[k] == b[k]) || std::signbit(a[k]) != std::signbit(b[k])) return false;
  return true;
}

// S = cM M + cC C_t + cK K_t with the tangents taken at (u, v, t).
struct IterationMatrix {
  double cM = 0.0, cC = 0.0, cK = 1.0;
  const Vector* u = nullptr;
  const Vector* v = nullptr;
  double t = 0.0;
};

// Dense: K_t and C_t from the model's tangent, S assembled into storage the caller gives (the LU's).
class DenseIterationMatrix {
 public:
  void resize(Index n) {
    Kt_.setZero(n, n);
    Ct_.setZero(n, n);
  }
  Index size() const { return Kt_.rows(); }

  template <class ModelT>
  void assemble(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference, Matrix& S) {
    if (Kt_.rows() != model.size()) resize(model.size());
    model.tangent(*im.u, *im.v, im.t, Kt_, Ct_, st, finite_difference);
    const Index n = S.rows();
    const double *K = Kt_.data(), *C = Ct_.data();
    double* out = S.data();
    for (Index ij = 0; ij < n * n; ++ij) out[ij] = im.cK * K[ij];
    const auto& mass = model.mass();
    if (mass.is_diagonal()) {
      const double* m = mass.diagonal_entries().data();
      for (Index i = 0; i < n; ++i) out[i + i * n] += im.cM * m[i];
    } else {
      mass.for_each_entry([&](Index i, Index j, double m) { out[i + j * n] += im.cM * m; });
    }
    if (model.uses_velocity())
      for (Index ij = 0; ij < n * n; ++ij) out[ij] += im.cC * C[ij];
  }

  // out = C_t x (the last tangent)
  void multiply_C(const Vector& x, Vector& out) const { out.noalias() = Ct_ * x; }
  Vector tangent_diagonal() const { return Kt_.diagonal(); }
  Index first_nonfinite_tangent_row() const {
    if (Kt_.allFinite() && Ct_.allFinite()) return -1;
    Index dof = 0;
    while (dof + 1 < Kt_.rows() && Kt_.row(dof).allFinite() && Ct_.row(dof).allFinite()) ++dof;
    return dof;
  }

 private:
  Matrix Kt_, Ct_;
};

// Sparse: set up once per stepper, the pattern of S is the union of the mass, the linear K and C
// and the entries of the nonlinear tangent; each contribution gets its position in S's values, so
// that every assembly only adds numbers into place (no search, no allocation).
class SparseIterationMatrix {
 public:
  bool ready() const { return ready_; }
  const SparseMatrix& matrix() const { return S_; }
  SparseMatrix& matrix() { return S_; }  // (its values, to fill from another layout)
  Index nonzeros() const { return static_cast<Index>(S_.nonZeros()); }
  // Symmetric S: symmetric K and C (every effect's g g^T is).
  bool symmetric() const { return symmetric_; }

  template <class ModelT>
  void setup(const ModelT& model) {
    const Index n = model.size();
    retargeted_ = have_base_ = false;
    velocity_ = model.uses_velocity();
    kent_.clear();
    cent_.clear();
    model.tangent_entries(kent_, cent_);
    if (!velocity_) cent_.clear();
    kvals_.assign(kent_.size(), 0.0);
    cvals_.assign(cent_.size(), 0.0);
    // The pattern of S: every contribution, with a zero value (duplicates merge).
    std::vector<Eigen::Triplet<double, int>> all;
    model.mass().for_each_entry([&](Index i, Index j, double) { all.emplace_back(int(i), int(j), 0.0); });
    add_pattern(model.K(), all);
    if (velocity_) add_pattern(model.C(), all);
    for (const Entry& e : kent_) all.emplace_back(e.row, e.col, 0.0);
    for (const Entry& e : cent_) all.emplace_back(e.row, e.col, 0.0);
    S_.resize(n, n);
    S_.setFromTriplets(all.begin(), all.end());
    S_.makeCompressed();
    all.clear();
    all.shrink_to_fit();
    // Where each contribution goes.
    posM_.clear();
    mvals_.clear();
    model.mass().for_each_entry([&](Index i, Index j, double m) {
      posM_.push_back(position(S_, int(i), int(j)));
      mvals_.push_back(m);
    });
    positions_of(model.K(), S_, posK_);
    if (velocity_) positions_of(model.C(), S_, posC_);
    positions_of(kent_, S_, posNK_);
    positions_of(cent_, S_, posNC_);
    // C_t alone, for the incremental format's C_t (v1 - v_n).
    if (velocity_) {
      Ct_.resize(n, n);
      for (const Entry& e : cent_) all.emplace_back(e.row, e.col, 0.0);
      add_pattern(model.C(), all);
      Ct_.setFromTriplets(all.begin(), all.end());
      Ct_.makeCompressed();
      positions_of(model.C(), Ct_, posCtC_);
      positions_of(cent_, Ct_, posCtN_);
    }
    poll_interrupt();
    symmetric_ = is_symmetric(model.K()) && (!velocity_ || is_symmetric(model.C()));
    kdiag_.setZero(n);
    ready_ = true;
  }

  // S at the tangent of (u, v, t), into values(); false if the tangent is not finite. K_t and C_t are
  // summed entry by entry in the order of the effects, then their linear parts, and S = c_K K_t + c_M M
  // + c_C C_t: the operations of the dense assembly (DenseIterationMatrix), so that both give the same
  // S, bit for bit. The linear parts and the mass are laid out in S's storage once.
  template <class ModelT>
  bool assemble(ModelT& model, const IterationMatrix& im, Stats& st) {
    if (!ready_) setup(model);
    if (!have_base_) linear_parts(model);
    const size_t m = static_cast<size_t>(num_read());
    std::fill(tk_.begin(), tk_.end(), 0.0);
    if (velocity_) std::fill(tc_.begin(), tc_.end(), 0.0);
    // The tangent's values, each added into K_t's (and C_t's) place in S's storage as it is evaluated.
    // x - x is 0 for a finite x and NaN otherwise: one sum tells whether every entry is finite.
    const double finite = model.tangent_add(*im.u, *im.v, im.t,
                                            TangentOut{kvals_.data(), cvals_.data(), posNK_.data(), posNC_.data(),
                                                       tk_.data(), velocity_ ? tc_.data() : nullptr},
                                            kvals_.size(), cvals_.size(), st);
    const double cK = im.cK, cM = im.cM, cC = im.cC;
    double* __restrict s = values();
    const double *__restrict tk = tk_.data(), *__restrict kl = klin_.data();
    // c_M M is kept while c_M does not change (a run of one step length); the same products.
    if (!(cM == mterm_c_)) {
      const double* __restrict ml = mlin_.data();
      double* __restrict mt = mterm_.data();
      for (size_t q = 0; q < m; ++q) mt[q] = cM * ml[q];
      mterm_c_ = cM;
    }
    const double* __restrict mt = mterm_.data();
    // Without a linear K, tk + 0 is tk (up to the sign of a zero, which the sum with c_M M then drops).
    if (has_klin_)
      for (size_t q = 0; q < m; ++q) s[q] = cK * (tk[q] + kl[q]) + mt[q];
    else
      for (size_t q = 0; q < m; ++q) s[q] = cK * tk[q] + mt[q];
    if (velocity_) {
      const double *__restrict tc = tc_.data(), *__restrict cl = clin_.data();
      for (size_t q = 0; q < m; ++q) s[q] += cC * (tc[q] + cl[q]);
      double* c = Ct_.valuePtr();  // C_t alone (the incremental format's C_t (v1 - v_n))
      std::fill_n(c, Ct_.nonZeros(), 0.0);
      scatter(posCtN_, cvals_.data(), c);
      add_values(model.C(), posCtC_, c);
    }
    K_ = &model.K();
    return finite == 0.0;
  }

  // The tangent alone (the low-rank update's A is made from it: low_rank.hpp): its entries' values, and
  // C_t for multiply_C(); false if the tangent is not finite. S's values are not touched.
  template <class ModelT>
  bool assemble_tangent(ModelT& model, const IterationMatrix& im, Stats& st) {
    if (!ready_) setup(model);
    model.tangent_values(*im.u, *im.v, im.t, kvals_.data(), cvals_.data(), st);
    double finite = 0.0;
    for (double x : kvals_) finite += x - x;
    if (velocity_) {
      for (double x : cvals_) finite += x - x;
      double* c = Ct_.valuePtr();
      std::fill_n(c, Ct_.nonZeros(), 0.0);
      scatter(posCtN_, cvals_.data(), c);
      add_values(model.C(), posCtC_, c);
    }
    K_ = &model.K();
    return finite == 0.0;
  }
  // The nonlinear tangent's entries (C's empty where the model does not use velocity), and their values
  // at the last assembly.
  const std::vector<Entry>& k_entries() const { return kent_; }
  const std::vector<Entry>& c_entries() const { return cent_; }
  const double* k_values() const { return kvals_.data(); }
  const double* c_values() const { return cvals_.data(); }

  // Where assemble() writes S: matrix()'s values (compressed columns), or the layout of a
  // factorisation that reads S in its own storage (retarget()).
  double* values() { return retargeted_ ? target_.data() : S_.valuePtr(); }
  const double* values() const { return retargeted_ ? target_.data() : S_.valuePtr(); }
  Index num_values() const { return retargeted_ ? static_cast<Index>(target_.size()) : static_cast<Index>(S_.nonZeros()); }
  // The first num_read() of them are the ones read (the rest: retarget()'s places of their own for what
  // the factorisation does not read, never formed into S).
  Index num_read() const { return retargeted_ ? read_ : static_cast<Index>(S_.nonZeros()); }
  // From now on S is assembled into a storage of `size` values, the k-th stored value of matrix() going
  // to to[k] (to[k] < 0: not read by that factorisation, such as the upper triangle of a symmetric S):
  // one pass fewer than assembling the compressed columns and copying them over. matrix() keeps its
  // pattern (and stale values). What is not read goes past `size`, each contribution to a place of its
  // own: added into one place, they would wait on each other's stores.
  void retarget(const std::vector<int>& to, Index size) {
    int spare = static_cast<int>(size);
    auto remap = [&](std::vector<int>& pos) {
      for (int& p : pos) p = to[static_cast<size_t>(p)] >= 0 ? to[static_cast<size_t>(p)] : spare++;
    };
    remap(posM_);
    remap(posK_);
    remap(posC_);
    remap(posNK_);
    remap(posNC_);
    target_.assign(static_cast<size_t>(spare), 0.0);
    read_ = size;
    retargeted_ = true;
    have_base_ = false;
  }

  void multiply_C(const Vector& x, Vector& out) const {
    if (velocity_)
      out.noalias() = Ct_ * x;
    else
      out.setZero();
  }
  // The diagonal of K_t at the last assembly.
  const Vector& tangent_diagonal() {
    kdiag_.setZero();
    if (K_ != nullptr)
      for (Index j = 0; j < K_->outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(*K_, j); it; ++it)
          if (it.row() == j) kdiag_[j] += it.value();
    for (size_t k = 0; k < kent_.size(); ++k)
      if (kent_[k].row == kent_[k].col) kdiag_[kent_[k].row] += kvals_[k];
    return kdiag_;
  }
  Index first_nonfinite_tangent_row() const {
    for (size_t k = 0; k < kvals_.size(); ++k)
      if (!std::isfinite(kvals_[k])) return kent_[k].row;
    for (size_t k = 0; k < cvals_.size(); ++k)
      if (!std::isfinite(cvals_[k])) return cent_[k].row;
    return -1;
  }

 private:
  static void add_pattern(const SparseMatrix& A, std::vector<Eigen::Triplet<double, int>>& out) {
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) out.emplace_back(it.row(), int(j), 0.0);
  }
  // The index in A's values of entry (i, j), which the pattern holds.
  static int position(const SparseMatrix& A, int i, int j) {
    const int* rows = A.innerIndexPtr();
    const int *b = rows + A.outerIndexPtr()[j], *e = rows + A.outerIndexPtr()[j + 1];
    return static_cast<int>(std::lower_bound(b, e, i) - rows);
  }
  static void positions_of(const SparseMatrix& A, const SparseMatrix& S, std::vector<int>& pos) {
    pos.clear();
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) pos.push_back(position(S, it.row(), int(j)));
  }
  static void positions_of(const std::vector<Entry>& entries, const SparseMatrix& S, std::vector<int>& pos) {
    pos.clear();
    pos.reserve(entries.size());
    for (const Entry& e : entries) pos.push_back(position(S, e.row, e.col));
  }
  // The mass and the linear K and C in S's storage (0 where they have no entry), and the work arrays
  // of K_t and C_t.
  template <class ModelT>
  void linear_parts(const ModelT& model) {
    const size_t m = static_cast<size_t>(num_values());
    mlin_.assign(m, 0.0);
    klin_.assign(m, 0.0);
    scatter(posM_, mvals_.data(), mlin_.data());
    add_values(model.K(), posK_, klin_.data());
    has_klin_ = std::any_of(klin_.begin(), klin_.end(), [](double x) { return x != 0.0; });
    mterm_.assign(m, 0.0);
    mterm_c_ = std::numeric_limits<double>::quiet_NaN();
    tk_.assign(m, 0.0);
    if (velocity_) {
      clin_.assign(m, 0.0);
      add_values(model.C(), posC_, clin_.data());
      tc_.assign(m, 0.0);
    }
    have_base_ = true;
  }
  // s[pos[k]] += x[k] for every k, in order; returns the sum of x[k] - x[k] (0 unless some x[k] is not finite).
  static double scatter(const std::vector<int>& pos, const double* __restrict x, double* __restrict s) {
    const int* __restrict p = pos.data();
    double nonfinite = 0.0;
    for (size_t k = 0, m = pos.size(); k < m; ++k) {
      s[p[k]] += x[k];
      nonfinite += x[k] - x[k];
    }
    return nonfinite;
  }
  // S[pos[k]] += A.values[k] (A's values in its storage order, which positions_of followed).
  static void add_values(const SparseMatrix& A, const std::vector<int>& pos, double* s) {
    scatter(pos, A.valuePtr(), s);
  }
  static bool is_symmetric(const SparseMatrix& A) {
    if (A.nonZeros() == 0) return true;
    const SparseMatrix D = SparseMatrix(A.transpose()) - A;
    double dmax = 0.0, amax = 0.0;
    for (Index k = 0; k < D.nonZeros(); ++k) dmax = std::max(dmax, std::abs(D.valuePtr()[k]));
    for (Index k = 0; k < A.nonZeros(); ++k) amax = std::max(amax, std::abs(A.valuePtr()[k]));
    return dmax <= 1e-14 * amax;
  }

  bool ready_ = false, velocity_ = false, symmetric_ = true, retargeted_ = false;
  SparseMatrix S_, Ct_;
  std::vector<double> target_;  // S in a factorisation's own layout (retarget())
  std::vector<double> mlin_, klin_, clin_;  // M and the linear K and C in S's storage (values())
  std::vector<double> tk_, tc_;             // K_t and C_t being summed, in S's storage
  std::vector<double> mterm_;               // c_M M in S's storage, for c_M = mterm_c_
  double mterm_c_ = 0.0;
  bool has_klin_ = false;                   // a linear K with a nonzero entry
  Index read_ = 0;                          // retarget()'s size
  bool have_base_ = false;
  const SparseMatrix* K_ = nullptr;
  std::vector<Entry> kent_, cent_;
  std::vector<double> kvals_, cvals_, mvals_;
  std::vector<int> posM_, posK_, posC_, posNK_, posNC_, posCtC_, posCtN_;
  Vector kdiag_;
};

}  // namespace nvib
