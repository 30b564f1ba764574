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
    // The mass's entries, in its column order, as compressed columns.
    std::vector<int> mptr(static_cast<size_t>(n) + 1, 0), mrows;
    mvals_.clear();
    model.mass().for_each_entry([&](Index i, Index j, double m) {
      ++mptr[static_cast<size_t>(j) + 1];
      mrows.push_back(static_cast<int>(i));
      mvals_.push_back(m);
    });
    for (size_t j = 0; j < static_cast<size_t>(n); ++j) mptr[j + 1] += mptr[j];
    // The pattern of S: every contribution (duplicates merge), and where each goes.
    // (K and C are 0 x 0 where the model has none.)
    std::vector<Columns> columns{Columns{mptr.data(), mrows.data()}};
    std::vector<std::vector<int>*> column_pos{&posM_};
    posK_.clear();
    posC_.clear();
    posCtC_.clear();
    const bool has_K = model.K().outerSize() == n, has_C = velocity_ && model.C().outerSize() == n;
    if (has_K) {
      columns.push_back(Columns::of(model.K()));
      column_pos.push_back(&posK_);
    }
    if (has_C) {
      columns.push_back(Columns::of(model.C()));
      column_pos.push_back(&posC_);
    }
    union_pattern(n, columns, column_pos, {&kent_, &cent_}, {&posNK_, &posNC_}, S_);
    // C_t alone, for the incremental format's C_t (v1 - v_n).
    if (velocity_) {
      columns.clear();
      column_pos.clear();
      if (has_C) {
        columns.push_back(Columns::of(model.C()));
        column_pos.push_back(&posCtC_);
      }
      union_pattern(n, columns, column_pos, {&cent_}, {&posCtN_}, Ct_);
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
  // Entries given by compressed columns (the rows of column j at row[ptr[j]] .. row[ptr[j + 1] - 1]).
  struct Columns {
    const int* ptr;
    const int* row;
    static Columns of(const SparseMatrix& A) { return {A.outerIndexPtr(), A.innerIndexPtr()}; }
  };
  // out = the pattern of every source, compressed columns with ascending rows (zero values), and for each
  // source entry its index in out's values (column sources in their storage order, entry lists in
  // theirs). Column by column with a marker per row: no sort of all the entries and no search, a sort of
  // each column's few rows.
  static void union_pattern(Index n, const std::vector<Columns>& columns, const std::vector<std::vector<int>*>& column_pos,
                            const std::vector<const std::vector<Entry>*>& lists,
                            const std::vector<std::vector<int>*>& list_pos, SparseMatrix& out) {
    const size_t N = static_cast<size_t>(n);
    // The lists' entries by column (a counting sort of their rows, each with where its position goes).
    std::vector<int> lptr(N + 1, 0);
    for (const auto* l : lists)
      for (const Entry& e : *l) ++lptr[static_cast<size_t>(e.col) + 1];
    for (size_t j = 0; j < N; ++j) lptr[j + 1] += lptr[j];
    std::vector<int> lrow(static_cast<size_t>(lptr[N]));
    std::vector<int*> lto(static_cast<size_t>(lptr[N]));
    {
      std::vector<int> next(lptr.begin(), lptr.end() - 1);
      for (size_t l = 0; l < lists.size(); ++l) {
        list_pos[l]->assign(lists[l]->size(), 0);
        for (size_t k = 0; k < lists[l]->size(); ++k) {
          const Entry& e = (*lists[l])[k];
          const size_t q = static_cast<size_t>(next[static_cast<size_t>(e.col)]++);
          lrow[q] = e.row;
          lto[q] = list_pos[l]->data() + k;
        }
      }
    }
    size_t total = lrow.size();
    for (size_t c = 0; c < columns.size(); ++c) {
      total += static_cast<size_t>(columns[c].ptr[N]);
      column_pos[c]->assign(static_cast<size_t>(columns[c].ptr[N]), 0);
    }
    std::vector<int> outer(N + 1, 0), inner, mark(N, -1), where(N, 0);
    inner.reserve(total);
    for (size_t j = 0; j < N; ++j) {
      const size_t first = inner.size();
      const int jj = static_cast<int>(j);
      auto add = [&](int r) {
        if (mark[static_cast<size_t>(r)] != jj) {
          mark[static_cast<size_t>(r)] = jj;
          inner.push_back(r);
        }
      };
      for (const Columns& c : columns)
        for (int q = c.ptr[j]; q < c.ptr[j + 1]; ++q) add(c.row[q]);
      for (int q = lptr[j]; q < lptr[j + 1]; ++q) add(lrow[static_cast<size_t>(q)]);
      std::sort(inner.begin() + static_cast<std::ptrdiff_t>(first), inner.end());
      for (size_t q = first; q < inner.size(); ++q) where[static_cast<size_t>(inner[q])] = static_cast<int>(q);
      for (size_t c = 0; c < columns.size(); ++c) {
        int* pos = column_pos[c]->data();
        for (int q = columns[c].ptr[j]; q < columns[c].ptr[j + 1]; ++q) pos[q] = where[static_cast<size_t>(columns[c].row[q])];
      }
      for (int q = lptr[j]; q < lptr[j + 1]; ++q) *lto[static_cast<size_t>(q)] = where[static_cast<size_t>(lrow[static_cast<size_t>(q)])];
      outer[j + 1] = static_cast<int>(inner.size());
    }
    out.resize(n, n);
    out.resizeNonZeros(static_cast<Index>(inner.size()));
    std::copy(outer.begin(), outer.end(), out.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), out.innerIndexPtr());
    std::fill_n(out.valuePtr(), inner.size(), 0.0);
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
  // scatter_add() over a list of places.
  static double scatter(const std::vector<int>& pos, const double* x, double* s) {
    return scatter_add(pos.data(), x, pos.size(), s);
  }
  // S[pos[k]] += A.values[k] (A's values in its storage order, which union_pattern() followed).
  static void add_values(const SparseMatrix& A, const std::vector<int>& pos, double* s) {
    scatter(pos, A.valuePtr(), s);
  }
  // A = A^T to 1e-14 of its largest entry (an entry without a stored twin against 0), entry by entry, in
  // one pass (no transposed copy, no difference matrix): the columns are walked in order, so the twins
  // sought in column i come in ascending rows and a cursor per column finds each.
  static bool is_symmetric(const SparseMatrix& A) {
    if (A.nonZeros() == 0) return true;
    const int *ptr = A.outerIndexPtr(), *row = A.innerIndexPtr();
    const double* x = A.valuePtr();
    double amax = 0.0;
    for (Index k = 0; k < A.nonZeros(); ++k) amax = std::max(amax, std::abs(x[k]));
    const double tol = 1e-14 * amax;
    std::vector<int> cursor(ptr, ptr + A.outerSize());
    for (int j = 0; j < static_cast<int>(A.outerSize()); ++j)
      for (int q = ptr[j]; q < ptr[j + 1]; ++q) {
        const int i = row[q];
        if (i == j) continue;
        int& c = cursor[static_cast<size_t>(i)];
        while (c < ptr[i + 1] && row[c] < j) ++c;
        const double twin = c < ptr[i + 1] && row[c] == j ? x[c] : 0.0;
        if (!(std::abs(x[q] - twin) <= tol)) return false;
      }
    return true;
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
