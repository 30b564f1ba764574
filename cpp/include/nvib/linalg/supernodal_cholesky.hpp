// Supernodal sparse Cholesky factorisation, LL^T and unpivoted LDL^T, with the contract of
// OrderedCholesky (analyze / factorize_values / solve_in_place / pivots / dof_pivots), for the
// matrices whose factor fills in (3-D solids with a consistent mass): columns of L with the same
// structure are stored together as dense column-major panels, and all the arithmetic between them
// is dense matrix-matrix products (Eigen's GEMM and TRSM) instead of the simplicial factorisation's
// one sparse column at a time.
//
// The algorithms, as described in the literature (the code is written from those descriptions):
//   - orderings: approximate minimum degree (Amestoy, Davis & Duff 1996; Eigen's AMDOrdering), and
//     nested dissection (George 1973) by multilevel bisection (Hendrickson & Leland 1995; Karypis &
//     Kumar 1998: heavy-edge matching, greedy growing, Fiduccia & Mattheyses 1982 refinement, a
//     vertex separator as the minimum vertex cover of the cut edges) on the graph compressed to one
//     vertex a node (Ashcraft 1995); nested dissection where its factor needs clearly fewer flops
//     and entries than AMD's (CHOLMOD chooses by flops alone; here the solves, which read the
//     entries, are most of a run's cost): on 3-D meshes nested dissection, 4-6x fewer flops; on
//     chains, bands and most 2-D meshes AMD;
//   - a postorder of the elimination tree, which leaves the fill unchanged and makes every supernode
//     a range of consecutive columns; the tree by Liu's algorithm with path compression (Liu 1990,
//     "The role of elimination trees in sparse factorization");
//   - column counts of L without forming it: Gilbert, Ng & Peyton 1994, in the form of Davis,
//     "Direct Methods for Sparse Linear Systems", SIAM 2006, ch. 4 (row subtrees, skeleton matrix,
//     least common ancestors by a disjoint-set forest);
//   - fundamental supernodes, then relaxed amalgamation: a child supernode is merged into its parent
//     when the explicit zeros this stores are few enough (Ashcraft & Grimes 1989; the three-tier rule
//     of CHOLMOD, Chen, Davis, Hager & Rajamanickam 2008);
//   - numeric factorisation: left-looking supernodal (Ng & Peyton 1993; Rothberg & Gupta 1993): each
//     supernode gathers the updates of the descendants that reach it (the schedule of these updates
//     is computed by analyze()), each a dense product of two row blocks of the descendant's panel,
//     subtracted through relative indices; then a blocked dense Cholesky (or LDL^T, unpivoted) of the
//     supernode's panel;
//   - the solve: forward and backward substitution by supernodes, dense triangular solves and
//     matrix-vector products on the panels (scalar loops for panels of a few columns).
//
// No heap allocation after analyze(): every workspace of the numeric phase and of the solve is sized
// there (the solve uses only the caller's vectors). Eigen's level-3 kernels take their packing
// buffers from the stack when these are at most EIGEN_STACK_ALLOCATION_LIMIT bytes, so every product
// and triangular solve is handed to Eigen in blocks of at most kEigenBlock rows, columns and depth
// (at most 2 x 128 KiB of stack with Eigen's default limit).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <list>
#include <mutex>
#include <numeric>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include "../base/types.hpp"

namespace nvib {

// Relaxed amalgamation (Ashcraft & Grimes 1989): a child supernode whose columns end right before its
// parent's begin is merged into the parent when the merged supernode has at most `always` columns, or
// at most `small` columns and a fraction of explicit zeros below `small_zeros`, or at most `medium`
// columns and below `medium_zeros`, or any size and below `large_zeros` (CHOLMOD's rule; its defaults
// 4, 16, 0.8, 48, 0.1, 0.05 made the chain's supernodes 16 columns of mostly zeros, 3x slower). The
// defaults were measured on 3-D hexahedral and 2-D quadrilateral meshes and a chain
// (benchmarks/factorize.py): on the meshes, whose nodes give supernodes of several columns anyway,
// anything from no relaxation to CHOLMOD's is within the noise; on the chain, pairs of columns are the
// fastest. All zero keeps the fundamental supernodes (no explicit zeros).
struct SupernodeRelaxation {
  int always = 2;
  int small = 8;
  double small_zeros = 0.3;
  int medium = 48;
  double medium_zeros = 0.1;
  double large_zeros = 0.05;
};

// The fill-reducing ordering. automatic: AMD, and where AMD's factor has large fronts nested dissection
// too, kept where it needs clearly fewer flops and entries (SupernodalCholesky::analyze).
enum class SupernodalOrdering { automatic, amd, nested_dissection };

namespace supernodal_detail {

using Panel = Eigen::Map<Matrix, 0, Eigen::OuterStride<>>;
using ConstPanel = Eigen::Map<const Matrix, 0, Eigen::OuterStride<>>;
using VecMap = Eigen::Map<Vector>;

// The largest multiple of 16, b, with b * b doubles within Eigen's stack allocation limit: Eigen's GEMM
// and TRSM packing buffers are at most (depth x rows) and (depth x columns), so with every dimension
// <= b they come from alloca, not malloc.
constexpr Index eigen_block() {
  Index b = 16;
  constexpr Index limit = static_cast<Index>(EIGEN_STACK_ALLOCATION_LIMIT);
  while ((b + 16) * (b + 16) * static_cast<Index>(sizeof(double)) <= limit) b += 16;
  return b;
}
constexpr Index kEigenBlock = eigen_block();

// Column block of the dense panel factorisation: the diagonal block is factorised by the scalar kernel,
// the rest by TRSM and GEMM (measured: 32 to 96 equal within the noise on the 3-D and 2-D meshes).
constexpr Index kPanelBlock = 48;
// Below this many columns a panel is factorised by the scalar kernel alone (no TRSM/GEMM calls).
constexpr Index kScalarPanel = 8;
// Below this many multiply-adds (rows x columns x depth) a descendant's update is applied by scalar
// loops straight into the target panel: below it the set-up of a GEMM call (blocking, packing) costs
// more than the arithmetic (2048 against 512 and 8192: equal within the noise).
constexpr Index kScalarUpdate = 2048;
// Width of the column blocks of the updates of lower triangles (descendant updates, trailing panel
// updates): each block is one GEMM from its diagonal down, so only the upper halves of the diagonal
// blocks are computed in vain (with the whole square, half the update flops of a 3-D mesh were).
constexpr Index kUpdateBlock = 32;
// Supernodes of at most this many columns are solved by scalar loops.
constexpr Index kScalarSolve = 8;

// C (m x n, ldc) -= A (m x k, lda) * B^T (B: n x k, ldb), all column-major.
inline void gemm_nt_sub(Index m, Index n, Index k, const double* A, Index lda, const double* B, Index ldb, double* C,
                        Index ldc) {
  constexpr Index b = kEigenBlock;
  for (Index k0 = 0; k0 < k; k0 += b) {
    const Index kk = std::min(b, k - k0);
    for (Index j0 = 0; j0 < n; j0 += b) {
      const Index nn = std::min(b, n - j0);
      const ConstPanel Bm(B + k0 * ldb + j0, nn, kk, Eigen::OuterStride<>(ldb));
      for (Index i0 = 0; i0 < m; i0 += b) {
        const Index mm = std::min(b, m - i0);
        const ConstPanel Am(A + k0 * lda + i0, mm, kk, Eigen::OuterStride<>(lda));
        Panel Cm(C + j0 * ldc + i0, mm, nn, Eigen::OuterStride<>(ldc));
        Cm.noalias() -= Am * Bm.transpose();
      }
    }
  }
}

// B (m x k, ldb) <- B T^{-T}, T (k x k, ldt) lower triangular, with a unit diagonal when Unit (T's
// stored diagonal, D of LDL^T, is then not read). k <= kEigenBlock.
template <bool Unit>
inline void trsm_right_lower_t(Index m, Index k, const double* T, Index ldt, double* B, Index ldb) {
  if (k <= 16) {  // column by column: B_j <- (B_j - sum_{q<j} B_q T_jq) / T_jj
    for (Index j = 0; j < k; ++j) {
      double* bj = B + j * ldb;
      for (Index q = 0; q < j; ++q) {
        const double f = T[q * ldt + j];
        const double* bq = B + q * ldb;
        for (Index i = 0; i < m; ++i) bj[i] -= f * bq[i];
      }
      if constexpr (!Unit) {
        const double inv = 1.0 / T[j * ldt + j];
        for (Index i = 0; i < m; ++i) bj[i] *= inv;
      }
    }
    return;
  }
  const ConstPanel Tm(T, k, k, Eigen::OuterStride<>(ldt));
  for (Index i0 = 0; i0 < m; i0 += kEigenBlock) {
    Panel Bm(B + i0, std::min(kEigenBlock, m - i0), k, Eigen::OuterStride<>(ldb));
    if constexpr (Unit)
      Tm.transpose().template triangularView<Eigen::UnitUpper>().template solveInPlace<Eigen::OnTheRight>(Bm);
    else
      Tm.transpose().template triangularView<Eigen::Upper>().template solveInPlace<Eigen::OnTheRight>(Bm);
  }
}

// Forward substitution through a supernode of NC <= kScalarSolve columns (its panel L: nr rows,
// column-major, its row indices rs, x1 its NC entries of w): the triangle, then each row below it takes
// its NC products in column order, the index and the entry of w read and written once a row. Each
// entry of w gets the same subtractions in the same order as column by column: the same bits.
template <bool LDLT, int NC>
inline void forward_small(const double* L, Index nr, const int* rs, double* x1, double* w) {
  double xs[NC];
  for (int k = 0; k < NC; ++k) {
    const double* lk = L + k * nr;
    if constexpr (!LDLT) x1[k] /= lk[k];
    const double xk = x1[k];
    xs[k] = xk;
    for (int i = k + 1; i < NC; ++i) x1[i] -= lk[i] * xk;
  }
  for (Index i = NC; i < nr; ++i) {
    double v = w[rs[i]];
    for (int k = 0; k < NC; ++k) v -= L[k * nr + i] * xs[k];
    w[rs[i]] = v;
  }
}

// Backward substitution through the same supernode: the rows below the triangle first (as the dense
// path's x1 -= L21^T t), each column's sum in P interleaved partial sums (P * NC >= 4 independent
// chains: one sum alone waits on each addition), then the triangle.
template <bool LDLT, int NC>
inline void backward_small(const double* L, Index nr, const int* rs, double* x1, const double* w) {
  constexpr int P = NC >= 4 ? 1 : (NC == 1 ? 4 : 2);
  double s[P][NC] = {};
  Index i = NC;
  for (; i + P <= nr; i += P)
    for (int p = 0; p < P; ++p) {
      const double g = w[rs[i + p]];
      for (int k = 0; k < NC; ++k) s[p][k] += L[k * nr + i + p] * g;
    }
  for (; i < nr; ++i) {
    const double g = w[rs[i]];
    for (int k = 0; k < NC; ++k) s[0][k] += L[k * nr + i] * g;
  }
  for (int k = 0; k < NC; ++k) {
    double t = s[0][k];
    for (int p = 1; p < P; ++p) t += s[p][k];
    x1[k] -= t;
  }
  for (int k = NC - 1; k >= 0; --k) {
    const double* lk = L + k * nr;
    double v = x1[k];
    for (int q = k + 1; q < NC; ++q) v -= lk[q] * x1[q];
    x1[k] = LDLT ? v : v / lk[k];
  }
}

template <bool LDLT, bool Forward, int NC = 1>
inline void solve_small(Index nc, const double* L, Index nr, const int* rs, double* x1, double* w) {
  if constexpr (NC < kScalarSolve) {
    if (nc != NC) return solve_small<LDLT, Forward, NC + 1>(nc, L, nr, rs, x1, w);
  }
  if constexpr (Forward)
    forward_small<LDLT, NC>(L, nr, rs, x1, w);
  else
    backward_small<LDLT, NC>(L, nr, rs, x1, w);
}

// Right-looking scalar factorisation of the m x k column-major block a (lda), m >= k: its top k x k
// is factorised (LL^T, or unit-lower LDL^T with D on the diagonal) and the rows below are divided by
// it. Returns the local column of a failing pivot, or -1.
template <bool LDLT>
inline Index panel_scalar(double* a, Index m, Index k, Index lda) {
  for (Index c = 0; c < k; ++c) {
    double* ac = a + c * lda;
    const double d = ac[c];
    if constexpr (LDLT) {
      if (d == 0.0 || !std::isfinite(d)) return c;
      const double inv = 1.0 / d;
      for (Index j = c + 1; j < k; ++j) {  // a_ij -= l_jc (l_ic d): a_ic is still l_ic d here
        const double f = ac[j] * inv;
        double* aj = a + j * lda;
        for (Index i = j; i < m; ++i) aj[i] -= f * ac[i];
      }
      for (Index i = c + 1; i < m; ++i) ac[i] *= inv;
    } else {
      if (!(d > 0.0) || !std::isfinite(d)) return c;
      const double l = std::sqrt(d), inv = 1.0 / l;
      ac[c] = l;
      for (Index i = c + 1; i < m; ++i) ac[i] *= inv;
      for (Index j = c + 1; j < k; ++j) {
        const double f = ac[j];
        double* aj = a + j * lda;
        for (Index i = j; i < m; ++i) aj[i] -= f * ac[i];
      }
    }
  }
  return -1;
}

// ---------------------------------------------------------------------------------------------------
// Nested dissection (George 1973) by multilevel graph bisection (Hendrickson & Leland 1995; Karypis &
// Kumar 1998): for 3-D meshes it needs several times fewer flops than minimum degree. The graph is
// first compressed (rows of A with the same pattern, the DOFs of one node, become one vertex, Ashcraft
// 1995); each bisection coarsens by heavy-edge matching, bisects the coarsest graph by greedy growing,
// refines the edge cut at each finer level with Fiduccia-Mattheyses passes, and turns the final edge cut
// into a vertex separator by a minimum vertex cover of the cut edges (Koenig's theorem on a maximum
// matching). Parts of at most kLeaf vertices are ordered by AMD.
// ---------------------------------------------------------------------------------------------------

struct Graph {  // undirected, no self loops; compressed rows with edge and vertex weights
  std::vector<int> xadj{0}, adj, ew, vw;
  int size() const { return static_cast<int>(vw.size()); }
};

struct Rng {  // xorshift64*: reproducible orderings on every platform
  std::uint64_t s = 0x9E3779B97F4A7C15ull;
  int below(int n) {
    s ^= s >> 12, s ^= s << 25, s ^= s >> 27;
    return static_cast<int>(((s * 0x2545F4914F6CDD1Dull) >> 33) % static_cast<std::uint64_t>(n));
  }
};

constexpr int kLeaf = 120;        // parts this small are ordered by minimum degree
constexpr int kCoarsest = 100;    // coarsening stops at this many vertices
constexpr double kImbalance = 0.1;  // each side of a bisection at most (1 + this) / 2 of the weight

// Heavy-edge matching (Karypis & Kumar 1998): each vertex, in random order, is paired with the
// unmatched neighbour of heaviest edge; the pairs are the coarse graph's vertices.
inline bool coarsen(const Graph& g, Graph& c, std::vector<int>& cmap, Rng& rng) {
  const int n = g.size();
  std::vector<int> order(n), match(n, -1);
  std::iota(order.begin(), order.end(), 0);
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[rng.below(i + 1)]);
  long total = 0;
  for (int w : g.vw) total += w;
  const long maxvw = std::max<long>(1, static_cast<long>(1.5 * static_cast<double>(total) / kCoarsest));
  cmap.assign(n, -1);
  std::vector<int> first;  // coarse vertex -> a fine vertex of it (its partner is match[])
  for (int v : order) {
    if (match[v] != -1) continue;
    int best = -1, bw = -1;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (match[u] == -1 && g.ew[e] > bw && g.vw[v] + g.vw[u] <= maxvw) best = u, bw = g.ew[e];
    }
    const int cv = static_cast<int>(first.size());
    first.push_back(v);
    match[v] = best == -1 ? v : best;
    cmap[v] = cv;
    if (best != -1) match[best] = v, cmap[best] = cv;
  }
  const int cn = static_cast<int>(first.size());
  if (cn > 0.9 * n) return false;  // matching stalled: coarsening no longer pays
  c = Graph();
  c.vw.resize(cn);
  std::vector<int> slot(cn, -1);
  for (int cv = 0; cv < cn; ++cv) {
    const int v = first[cv], u = match[v];
    const size_t start = c.adj.size();
    c.vw[cv] = g.vw[v] + (u != v ? g.vw[u] : 0);
    for (int x : {v, u}) {
      for (int e = g.xadj[x]; e < g.xadj[x + 1]; ++e) {
        const int cu = cmap[g.adj[e]];
        if (cu == cv) continue;
        if (slot[cu] == -1) {
          slot[cu] = static_cast<int>(c.adj.size());
          c.adj.push_back(cu);
          c.ew.push_back(g.ew[e]);
        } else {
          c.ew[slot[cu]] += g.ew[e];
        }
      }
      if (u == v) break;
    }
    for (size_t k = start; k < c.adj.size(); ++k) slot[c.adj[k]] = -1;
    c.xadj.push_back(static_cast<int>(c.adj.size()));
  }
  return true;
}

// Fiduccia-Mattheyses refinement of a two-way edge cut (part[v] in {0, 1}): moves of the best gain that
// keep each side within maxw, each vertex once a pass, hill-climbing up to a limit, then back to the
// best cut seen. Returns the cut.
inline long fm_refine(const Graph& g, std::vector<int>& part, long maxw, int passes) {
  const int n = g.size();
  std::vector<long> id(n), ed(n);
  long w[2] = {0, 0};
  long cut = 0;
  for (int v = 0; v < n; ++v) {
    w[part[v]] += g.vw[v];
    id[v] = ed[v] = 0;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      (part[g.adj[e]] == part[v] ? id : ed)[v] += g.ew[e];
    cut += ed[v];
  }
  cut /= 2;
  std::vector<char> locked(n);
  std::vector<int> moves;
  const int limit = std::max(25, std::min(200, n / 20));
  for (int pass = 0; pass < passes; ++pass) {
    using Entry = std::pair<long, int>;
    std::vector<Entry> heap[2];
    auto push = [&](int v) {
      auto& h = heap[part[v]];
      h.emplace_back(ed[v] - id[v], v);
      std::push_heap(h.begin(), h.end());
    };
    std::fill(locked.begin(), locked.end(), 0);
    for (int v = 0; v < n; ++v)
      if (ed[v] > 0) push(v);
    moves.clear();
    const long start_cut = cut;
    long best_cut = cut, best_dev = std::labs(w[0] - w[1]);
    size_t best_moves = 0;
    for (;;) {
      int pick = -1;
      long pick_gain = 0;
      for (int s = 0; s < 2; ++s) {
        auto& h = heap[s];
        while (!h.empty()) {  // drop stale entries
          const Entry top = h.front();
          const int v = top.second;
          if (!locked[v] && part[v] == s && top.first == ed[v] - id[v] && ed[v] > 0) break;
          std::pop_heap(h.begin(), h.end());
          h.pop_back();
        }
        if (h.empty()) continue;
        const int v = h.front().second;
        if (w[1 - s] + g.vw[v] > maxw) continue;
        const long gain = h.front().first;
        if (pick == -1 || gain > pick_gain || (gain == pick_gain && w[s] > w[part[pick]]))  // ties: the heavier side
          pick = v, pick_gain = gain;
      }
      if (pick == -1) break;
      const int s = part[pick];
      auto& h = heap[s];
      std::pop_heap(h.begin(), h.end());
      h.pop_back();
      part[pick] = 1 - s;
      locked[pick] = 1;
      w[s] -= g.vw[pick];
      w[1 - s] += g.vw[pick];
      cut -= pick_gain;
      std::swap(id[pick], ed[pick]);
      moves.push_back(pick);
      for (int e = g.xadj[pick]; e < g.xadj[pick + 1]; ++e) {
        const int u = g.adj[e];
        const long we = g.ew[e];
        if (part[u] == s) {
          id[u] -= we, ed[u] += we;
        } else {
          id[u] += we, ed[u] -= we;
        }
        if (!locked[u] && ed[u] > 0) push(u);
      }
      const long dev = std::labs(w[0] - w[1]);
      if (cut < best_cut || (cut == best_cut && dev < best_dev)) {
        best_cut = cut, best_dev = dev, best_moves = moves.size();
      } else if (moves.size() - best_moves > static_cast<size_t>(limit)) {
        break;
      }
    }
    // Undo the moves after the best cut.
    for (size_t k = moves.size(); k > best_moves; --k) {
      const int v = moves[k - 1];
      const int s = part[v];
      part[v] = 1 - s;
      w[s] -= g.vw[v];
      w[1 - s] += g.vw[v];
      std::swap(id[v], ed[v]);
      for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
        const int u = g.adj[e];
        const long we = g.ew[e];
        if (part[u] == s) {
          id[u] -= we, ed[u] += we;
        } else {
          id[u] += we, ed[u] -= we;
        }
      }
    }
    cut = best_cut;
    if (best_cut >= start_cut) break;
  }
  return cut;
}

// A bisection of the (small) coarsest graph: regions grown breadth-first from random seeds to half the
// weight, each refined; the smallest balanced cut.
inline void initial_bisection(const Graph& g, std::vector<int>& part, long maxw, Rng& rng) {
  const int n = g.size();
  long total = 0;
  for (int w : g.vw) total += w;
  std::vector<int> trial(n), queue;
  long best = std::numeric_limits<long>::max();
  for (int t = 0; t < 8; ++t) {
    std::fill(trial.begin(), trial.end(), 1);
    long w0 = 0;
    queue.clear();
    size_t head = 0;
    while (w0 < total / 2) {
      if (head == queue.size()) {  // a new seed (the first, or another component)
        int seed = rng.below(n);
        for (int k = 0; k < n && trial[seed] == 0; ++k) seed = (seed + 1) % n;
        if (trial[seed] == 0) break;
        trial[seed] = 0;
        w0 += g.vw[seed];
        queue.push_back(seed);
        continue;
      }
      const int v = queue[head++];
      for (int e = g.xadj[v]; e < g.xadj[v + 1] && w0 < total / 2; ++e) {
        const int u = g.adj[e];
        if (trial[u] == 0) continue;
        trial[u] = 0;
        w0 += g.vw[u];
        queue.push_back(u);
      }
    }
    const long cut = fm_refine(g, trial, maxw, 8);
    long w1 = 0;
    for (int v = 0; v < n; ++v) w1 += trial[v] ? g.vw[v] : 0;
    const long penalty = (w1 > maxw || total - w1 > maxw) ? total * 1000 : 0;  // unbalanced: a last resort
    if (cut + penalty < best) best = cut + penalty, part = trial;
  }
}

// Vertex separator of g: part[v] becomes 0, 1 or 2 (the separator). Multilevel edge bisection, then a
// minimum vertex cover of the cut edges (the boundary vertices' bipartite graph) as separator.
inline void bisect(const Graph& g, std::vector<int>& part, Rng& rng) {
  std::vector<Graph> levels;
  std::vector<std::vector<int>> cmaps;
  const Graph* cur = &g;
  levels.reserve(64);
  while (cur->size() > kCoarsest && levels.size() < 60) {
    Graph c;
    std::vector<int> cmap;
    if (!coarsen(*cur, c, cmap, rng)) break;
    levels.push_back(std::move(c));
    cmaps.push_back(std::move(cmap));
    cur = &levels.back();
  }
  long total = 0;
  for (int w : g.vw) total += w;
  const long maxw = static_cast<long>((1.0 + kImbalance) * 0.5 * static_cast<double>(total)) + 1;
  std::vector<int> cpart;
  initial_bisection(*cur, cpart, maxw, rng);
  for (size_t l = levels.size(); l-- > 0;) {  // project to the finer graph and refine there
    const Graph& fine = l == 0 ? g : levels[l - 1];
    std::vector<int> fpart(fine.size());
    for (int v = 0; v < fine.size(); ++v) fpart[v] = cpart[cmaps[l][v]];
    fm_refine(fine, fpart, maxw, 6);
    cpart.swap(fpart);
  }
  part.swap(cpart);
  // Minimum vertex cover of the cut edges (Koenig): a maximum matching of side-0 boundary vertices to
  // side-1 ones by augmenting paths, then the vertices reached by alternating paths from the
  // unmatched side-0 ones.
  const int n = g.size();
  std::vector<int> mate(n, -1), seen(n, -1), stack, it(n);
  auto cut_edge = [&](int v, int e) { return part[g.adj[e]] != part[v]; };
  std::vector<int> b0;
  for (int v = 0; v < n; ++v) {
    if (part[v] != 0) continue;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      if (cut_edge(v, e)) {
        b0.push_back(v);
        break;
      }
  }
  for (int root : b0) {  // one augmenting-path search (depth first, iterative) from each side-0 vertex
    stack.assign(1, root);
    it[root] = g.xadj[root];
    seen[root] = root;
    while (!stack.empty()) {
      const int v = stack.back();
      bool advanced = false;
      while (it[v] < g.xadj[v + 1]) {
        const int e = it[v]++;
        const int u = g.adj[e];
        if (part[u] != 1 || seen[u] == root) continue;
        seen[u] = root;
        const int m = mate[u];
        if (m == -1) {  // augment along the stack
          int x = u;
          for (size_t k = stack.size(); k-- > 0;) {
            const int y = stack[k], next = mate[y];
            mate[y] = x, mate[x] = y;
            x = next;
          }
          stack.clear();
          advanced = true;
          break;
        }
        if (seen[m] != root) {
          seen[m] = root;
          it[m] = g.xadj[m];
          stack.push_back(m);
          advanced = true;
          break;
        }
      }
      if (!advanced) stack.pop_back();
    }
  }
  std::vector<char> reached(n, 0);
  std::vector<int> queue;
  for (int v : b0)
    if (mate[v] == -1) reached[v] = 1, queue.push_back(v);
  for (size_t h = 0; h < queue.size(); ++h) {
    const int v = queue[h];  // side 0: along cut edges to side 1, then along the matching back
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (part[u] != 1 || reached[u]) continue;
      reached[u] = 1;
      const int m = mate[u];
      if (m != -1 && !reached[m]) reached[m] = 1, queue.push_back(m);
    }
  }
  std::vector<int> sep;
  for (int v : b0)
    if (!reached[v]) sep.push_back(v);
  for (int v = 0; v < n; ++v)
    if (part[v] == 1 && reached[v]) sep.push_back(v);
  for (int v : sep) part[v] = 2;
}

// Minimum-degree order of a small graph (Eigen's AMD): order[k] = the k-th vertex.
inline void leaf_order(const Graph& g, int* order) {
  const int n = g.size();
  if (n <= 2) {
    for (int k = 0; k < n; ++k) order[k] = k;
    return;
  }
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(g.adj.size() + static_cast<size_t>(n));
  for (int v = 0; v < n; ++v) {
    t.emplace_back(v, v, 1.0);
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) t.emplace_back(g.adj[e], v, 1.0);
  }
  SparseMatrix P(n, n);
  P.setFromTriplets(t.begin(), t.end());
  Eigen::AMDOrdering<int> amd;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
  amd(P, pinv);
  for (int k = 0; k < n; ++k) order[k] = pinv.indices()[k];
}

// The subgraph induced by the vertices v with part[v] == which; ids: its vertex -> g's vertex.
inline void induced(const Graph& g, const std::vector<int>& part, int which, Graph& sub, std::vector<int>& ids,
                    std::vector<int>& local) {
  ids.clear();
  for (int v = 0; v < g.size(); ++v)
    if (part[v] == which) local[v] = static_cast<int>(ids.size()), ids.push_back(v);
  sub = Graph();
  sub.vw.reserve(ids.size());
  for (int v : ids) {
    sub.vw.push_back(g.vw[v]);
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (part[u] != which) continue;
      sub.adj.push_back(local[u]);
      sub.ew.push_back(g.ew[e]);
    }
    sub.xadj.push_back(static_cast<int>(sub.adj.size()));
  }
}

// Orders g's vertices: out[begin + k] = the global id (ids[v]) of the k-th; the two parts of each
// bisection first, their separator last.
inline void dissect(const Graph& g, const std::vector<int>& ids, std::vector<int>& out, int begin, Rng& rng) {
  const int n = g.size();
  std::vector<int> order(n);
  std::vector<int> part;
  if (n > kLeaf) {  // the lightest of a few separators of large graphs: one bisection's varies by 10 to 20 %
    const int tries = n > 1000 ? 3 : 1;
    long best = std::numeric_limits<long>::max();
    std::vector<int> trial;
    for (int t = 0; t < tries; ++t) {
      bisect(g, trial, rng);
      long sep = 0, w0 = 0, w1 = 0;
      for (int v = 0; v < n; ++v) (trial[v] == 2 ? sep : trial[v] == 0 ? w0 : w1) += g.vw[v];
      if (std::min(w0, w1) == 0) continue;
      if (sep < best) best = sep, part.swap(trial);
    }
    if (part.empty()) bisect(g, part, rng);
  }
  int count[3] = {0, 0, 0};
  for (int p : part) ++count[p];
  if (n <= kLeaf || 20 * std::min(count[0], count[1]) < n) {  // small, or no useful separator
    leaf_order(g, order.data());
    for (int k = 0; k < n; ++k) out[begin + k] = ids[order[k]];
    return;
  }
  std::vector<int> local(n);
  int at_sep = begin + count[0] + count[1];
  for (int v = 0; v < n; ++v)
    if (part[v] == 2) out[at_sep++] = ids[v];
  int at = begin;
  for (int which = 0; which < 2; ++which) {
    Graph sub;
    std::vector<int> sub_ids;
    induced(g, part, which, sub, sub_ids, local);
    for (int& v : sub_ids) v = ids[v];
    dissect(sub, sub_ids, out, at, rng);
    at += count[which];
  }
}

// Nested-dissection order of the symmetric pattern of A (its lower triangle read): perm[i] = the
// position of row i. The rows of one vertex of the compressed graph (the DOFs of a node) stay together.
inline void nested_dissection(const SparseMatrix& A, std::vector<int>& perm) {
  const int n = static_cast<int>(A.rows());
  // The full pattern, diagonal included, each row's columns sorted.
  SparseMatrix full(n, n);
  full = A.selfadjointView<Eigen::Lower>();
  std::vector<Index> xadj(n + 1, 0);
  std::vector<int> adj;
  adj.reserve(static_cast<size_t>(full.nonZeros()) + static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) {
    bool diag = false;
    for (SparseMatrix::InnerIterator it(full, j); it; ++it) {
      adj.push_back(static_cast<int>(it.row()));
      diag |= it.row() == j;
    }
    if (!diag) adj.push_back(j);
    std::sort(adj.begin() + xadj[j], adj.end());
    xadj[j + 1] = static_cast<Index>(adj.size());
  }
  // Compression (Ashcraft 1995, loosened): consecutive rows coupled to each other whose patterns share
  // at least 3/4 of their entries are one vertex, at most 8 rows a vertex. These are the DOFs of a node,
  // whose patterns can differ where couplings cancel exactly in the assembly and the sum was dropped;
  // neighbours along a grid line of a 1-D, 2-D or 3-D stencil share 2/3 at most and stay apart.
  auto similar = [&](int a, int b) {
    const int* la = adj.data() + xadj[a];
    const int* lb = adj.data() + xadj[b];
    const Index na = xadj[a + 1] - xadj[a], nb = xadj[b + 1] - xadj[b];
    if (!std::binary_search(la, la + na, b)) return false;
    Index common = 0;
    for (Index p = 0, q = 0; p < na && q < nb;) {
      if (la[p] < lb[q]) {
        ++p;
      } else if (lb[q] < la[p]) {
        ++q;
      } else {
        ++common, ++p, ++q;
      }
    }
    return 4 * common >= 3 * std::max(na, nb);
  };
  // First, though, aligned blocks of b rows (the DOFs of a node, numbered together) whose rows see the
  // same blocks, in 9 blocks out of 10: 2-D elements can leave a node's DOFs uncoupled to each other.
  auto blocks_agree = [&](int b) {
    if (n % b != 0) return false;
    const int nb = n / b;
    std::vector<int> mark(nb, -1);
    int agree = 0;
    for (int B = 0; B < nb; ++B) {
      int count0 = 0;
      for (Index k = xadj[B * b]; k < xadj[B * b + 1]; ++k)
        if (mark[adj[k] / b] != B) mark[adj[k] / b] = B, ++count0;
      bool same = true;
      for (int r = B * b + 1; r < (B + 1) * b && same; ++r) {
        int count = 0;
        for (Index k = xadj[r]; k < xadj[r + 1] && same; ++k) {
          const int blk = adj[k] / b;
          same = mark[blk] == B;
          if (k == xadj[r] || adj[k - 1] / b != blk) ++count;  // sorted: each block once
        }
        same = same && count == count0;
      }
      agree += same;
    }
    return 10 * agree >= 9 * nb;
  };
  int block = 1;
  for (int b = 6; b >= 2 && block == 1; --b)
    if (blocks_agree(b)) block = b;
  std::vector<int> group(n);
  int nc = 0;
  for (int j = 0, run = 0; j < n; ++j) {
    if (block > 1 ? j % block != 0 : (j > 0 && run < 8 && similar(j - 1, j))) {
      group[j] = group[j - 1], ++run;
    } else {
      group[j] = nc++, run = 1;
    }
  }
  Graph g;
  g.vw.assign(nc, 0);
  std::vector<int> mark(nc, -1);
  for (int j = 0; j < n; ++j) {  // a group's edges: the groups of its rows' columns
    const int c = group[j];
    ++g.vw[c];
    mark[c] = c;
    for (Index k = xadj[j]; k < xadj[j + 1]; ++k) {
      const int gu = group[adj[k]];
      if (mark[gu] == c) continue;
      mark[gu] = c;
      g.adj.push_back(gu);
      g.ew.push_back(1);
    }
    if (j + 1 == n || group[j + 1] != c) g.xadj.push_back(static_cast<int>(g.adj.size()));
  }
  std::vector<int> ids(nc), order(nc);
  std::iota(ids.begin(), ids.end(), 0);
  Rng rng;
  dissect(g, ids, order, 0, rng);
  // Expand: the rows of each group, in order, at its place.
  std::vector<int> gpos(nc + 1, 0);
  for (int k = 0; k < nc; ++k) gpos[k + 1] = gpos[k] + g.vw[order[k]];
  std::vector<int> start(nc);
  for (int k = 0; k < nc; ++k) start[order[k]] = gpos[k];
  perm.resize(n);
  for (int j = 0; j < n; ++j) perm[j] = start[group[j]]++;
}

// The fill-reducing orderings analyze() chose last, by the pattern they were chosen for: a batch or an
// incremental dynamic analysis runs one large model many times (each run's model built anew, with
// other loads), and the orderings (AMD, and nested dissection to compare with it) are most of an
// analysis (on a 14,640-DOF wall, 74 ms with them, 8 ms with the kept one). A pattern is known by its
// size, its entries and a 64-bit hash of its lower triangle; two patterns that share them are taken for
// one, which could only cost fill: any permutation gives a correct factorisation (the factor's pattern
// is computed from A's, not kept). Process-wide, for every thread (a lock around the list), the last
// kCapacity patterns.
struct OrderingCache {
  static constexpr size_t kCapacity = 8;
  struct Key {
    Index n = 0, nnz = 0;
    std::uint64_t hash = 0;
    SupernodalOrdering asked = SupernodalOrdering::automatic;
    bool operator==(const Key& o) const { return n == o.n && nnz == o.nnz && hash == o.hash && asked == o.asked; }
  };
  struct Item {
    Key key;
    SupernodalOrdering used = SupernodalOrdering::amd;
    std::vector<int> order;  // row of A -> its position (before the postorder)
  };

  // A's key: its lower triangle's pattern hashed (splitmix64's finaliser over each (row, column)), its
  // entries, the ordering asked for.
  static Key key_of(const SparseMatrix& A, SupernodalOrdering asked) {
    auto mix = [](std::uint64_t x) {
      x ^= x >> 30, x *= 0xbf58476d1ce4e5b9ull;
      x ^= x >> 27, x *= 0x94d049bb133111ebull;
      return x ^ (x >> 31);
    };
    Key k;
    k.n = A.rows();
    k.asked = asked;
    k.hash = mix(static_cast<std::uint64_t>(A.rows()));
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it)
        if (it.row() >= j) {
          k.hash = mix(k.hash ^ (static_cast<std::uint64_t>(it.row()) << 32 ^ static_cast<std::uint64_t>(j)));
          ++k.nnz;
        }
    return k;
  }
  // The ordering kept for `key` (and the one it is), if one is.
  bool find(const Key& key, std::vector<int>& order, SupernodalOrdering& used) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = locate(key);
    if (it == items_.end()) return false;
    items_.splice(items_.begin(), items_, it);
    order = it->order;
    used = it->used;
    ++hits_;
    return true;
  }
  void insert(Item item) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = locate(item.key);
    if (it != items_.end()) items_.erase(it);  // (another thread analysed the same pattern meanwhile)
    items_.push_front(std::move(item));
    if (items_.size() > kCapacity) items_.pop_back();
  }
  // Forgets every pattern (a benchmark of cold analyses clears it before each).
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    items_.clear();
  }
  // (patterns kept, orderings taken from the cache so far)
  std::pair<size_t, Index> counts() {
    std::lock_guard<std::mutex> lock(mutex_);
    return {items_.size(), hits_};
  }

 private:
  std::list<Item>::iterator locate(const Key& key) {
    return std::find_if(items_.begin(), items_.end(), [&](const Item& i) { return i.key == key; });
  }
  std::mutex mutex_;
  std::list<Item> items_;  // the most recently used first
  Index hits_ = 0;
};
inline OrderingCache& ordering_cache() {
  static OrderingCache cache;
  return cache;
}

}  // namespace supernodal_detail

template <bool LDLT>
class SupernodalCholesky {
 public:
  // The automatic ordering keeps nested dissection where its factor needs at most these fractions of
  // AMD's flops and entries (analyze()).
  static constexpr double kNestedDissectionFlops = 0.8;
  static constexpr double kNestedDissectionEntries = 0.95;
  // Read by analyze(); change it before analyze() to trade explicit zeros for larger dense blocks.
  SupernodeRelaxation relaxation;
  // Read by analyze(): the fill-reducing ordering (automatic: AMD, or nested dissection where it needs
  // fewer flops).
  SupernodalOrdering ordering = SupernodalOrdering::automatic;
  // From this many rows on, analyze() keeps its ordering for the next matrix of the same pattern
  // (supernodal_detail::OrderingCache) and takes it from there when it was kept.
  static constexpr Index kOrderingCacheFrom = 1000;

  // A: symmetric, square; its lower triangle is read (the pattern of every later A must be this one's,
  // in the same storage; entries of the upper triangle may be stored and are ignored).
  void analyze(const SparseMatrix& A);

  // The numeric factorisation of A (analyze()'s pattern); info() says whether it succeeded. Allocates
  // nothing.
  void factorize_values(const SparseMatrix& A);

  // Success, or NumericalIssue: a pivot that is not > 0 (LL^T) or is zero or not finite (LDL^T); the
  // factorisation then stops at that pivot and the factors must not be used.
  Eigen::ComputationInfo info() const { return info_; }

  // x <- A^{-1} x, through work (n entries, the caller's: the factors may be shared by threads). The n
  // entries of x serve as scratch in between. Allocates nothing.
  void solve_in_place(double* x, Vector& work) const;

  // The pivots in the factor's (permuted) order: D of LDL^T, or the squared diagonal of L of LL^T
  // (the D of the same matrix's LDL^T). Their signs give the inertia.
  const Vector& pivots() const { return D_; }

  // The pivot of each row of A (not of P A P^T): D of LDL^T, or the squared diagonal of L of LL^T.
  Vector dof_pivots() const {
    Vector out(n_);
    for (Index i = 0; i < n_; ++i) out[i] = D_[perm_[static_cast<size_t>(i)]];
    return out;
  }

  // Stored entries of L (its lower trapezoids, diagonal included, explicit zeros of the relaxed
  // supernodes included).
  Index nonzeros() const { return nnz_; }
  // The flop count of the numeric factorisation: sum over the stored columns of L of (entries)^2, the
  // explicit zeros counted (each column's division and its rank-1 update, a multiply-add two flops).
  double flops() const { return flops_; }
  // The same two numbers for the simplicial factorisation of the same ordering (no explicit zeros):
  // a caller chooses between the two with them (the supernodal one pays off when the flops per entry
  // of L are many, i.e. the supernodes are large).
  Index simplicial_nonzeros() const { return nnz_exact_; }
  double simplicial_flops() const { return flops_exact_; }

  Index rows() const { return n_; }
  Index supernodes() const { return nsuper_; }
  // The ordering analyze() used (amd or nested_dissection), and whether it was the one kept for this
  // pattern by an earlier analyze() (then no ordering was computed).
  SupernodalOrdering ordering_used() const { return used_; }
  bool ordering_reused() const { return ordering_reused_; }
  // Row i of A is row permutation()[i] of P A P^T = L D L^T.
  const std::vector<int>& permutation() const { return perm_; }

  // L of P A P^T as a sparse matrix (unit diagonal for LDL^T), explicit zeros dropped; allocates (for
  // tests and inspection).
  SparseMatrix matrix_l() const;

 private:
  void update_from(Index d, Index p, Index p1, Index s, double* Ls);
  bool factor_panel(double* L, Index nr, Index nc);

  Index n_ = 0, nsuper_ = 0, nnz_ = 0, nnz_exact_ = 0;
  double flops_ = 0.0, flops_exact_ = 0.0;
  Eigen::ComputationInfo info_ = Eigen::Success;
  SupernodalOrdering used_ = SupernodalOrdering::amd;
  bool ordering_reused_ = false;
  std::vector<int> perm_;              // row of A -> row of P A P^T
  std::vector<int> super_start_;       // supernode s: columns super_start_[s] ... super_start_[s+1]-1
  std::vector<int> super_of_;          // column -> its supernode
  std::vector<Index> row_ptr_;         // supernode s: its rows rows_[row_ptr_[s] ...], ascending, its columns first
  std::vector<int> rows_;
  std::vector<Index> val_ptr_;         // supernode s: its panel (rows x columns, column-major) at values_[val_ptr_[s]]
  std::vector<double> values_;
  std::vector<Index> asm_ptr_;         // supernode s: A's values a[asm_src_[k]] go to its panel at asm_dst_[k]
  std::vector<Index> asm_src_, asm_dst_;
  std::vector<Index> upd_ptr_;         // supernode s: the updates upd_*[upd_ptr_[s] ...] it receives:
  std::vector<int> upd_d_;             //   from descendant upd_d_, whose rows upd_p_ ... upd_p1_-1 are
  std::vector<int> upd_p_, upd_p1_;    //   columns of s (and rows upd_p_ ... to its end are rows of s)
  // Workspaces of the numeric phase, sized by analyze().
  std::vector<int> map_;               // row of P A P^T -> its local row in the supernode being factorised
  std::vector<int> rel_;               // the local rows in the target of an update's rows
  std::vector<double> cbuf_;           // an update's dense product before it is scattered
  std::vector<double> wbuf_;           // LDL^T: a row block scaled by D
  Vector D_;
};

// ---------------------------------------------------------------------------------------------------
// Symbolic analysis.
// ---------------------------------------------------------------------------------------------------

template <bool LDLT>
void SupernodalCholesky<LDLT>::analyze(const SparseMatrix& A) {
  const int n = static_cast<int>(A.rows());
  n_ = n;
  info_ = Eigen::Success;
  const size_t N = static_cast<size_t>(n);
  auto at = [](auto& v, auto i) -> auto& { return v[static_cast<size_t>(i)]; };
  // A's lower triangle: column j's stored entries k in [first(j), last(j)) of the value array.
  auto first = [&](int j) -> Index { return A.outerIndexPtr()[j]; };
  auto last = [&](int j) -> Index {
    return A.isCompressed() ? A.outerIndexPtr()[j + 1] : A.outerIndexPtr()[j] + A.innerNonZeroPtr()[j];
  };

  // 1. Fill-reducing orderings: AMD on the pattern of A + A^T (as OrderedCholesky::analyze) and nested
  // dissection; the one whose factor needs fewer flops is kept (the counts cost O(nnz(A)) each; CHOLMOD
  // chooses between its orderings so).
  std::vector<int> amd, nd;  // row of A -> its position
  const bool cached = n >= kOrderingCacheFrom;
  supernodal_detail::OrderingCache::Key key;
  if (cached) key = supernodal_detail::OrderingCache::key_of(A, ordering);
  std::vector<int> kept;
  SupernodalOrdering kept_used = SupernodalOrdering::amd;
  ordering_reused_ = cached && supernodal_detail::ordering_cache().find(key, kept, kept_used);
  if (n > 0 && !ordering_reused_ && ordering != SupernodalOrdering::nested_dissection) {
    amd.resize(N);
    SparseMatrix full(n, n);
    full = A.selfadjointView<Eigen::Lower>();
    Eigen::AMDOrdering<int> amd_ordering;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
    amd_ordering(full, pinv);  // the inverse permutation: position -> row of A
    for (int i = 0; i < n; ++i) at(amd, pinv.indices()[i]) = i;
  }
  if (n > 0 && !ordering_reused_ && ordering == SupernodalOrdering::nested_dissection)
    supernodal_detail::nested_dissection(A, nd);

  // The strictly upper pattern of P A P^T, by columns, for a permutation p: what the tree algorithms read.
  std::vector<Index> up_ptr(N + 1);
  std::vector<int> up_row;
  auto upper_pattern = [&](const std::vector<int>& p) {
    std::fill(up_ptr.begin(), up_ptr.end(), 0);
    for (int j = 0; j < n; ++j)
      for (Index k = first(j); k < last(j); ++k) {
        const int i = A.innerIndexPtr()[k];
        if (i > j) ++at(up_ptr, std::max(at(p, i), at(p, j)) + 1);
      }
    for (int j = 0; j < n; ++j) at(up_ptr, j + 1) += at(up_ptr, j);
    up_row.resize(static_cast<size_t>(up_ptr[N]));
    std::vector<Index> next(up_ptr.begin(), up_ptr.end() - 1);
    for (int j = 0; j < n; ++j)
      for (Index k = first(j); k < last(j); ++k) {
        const int i = A.innerIndexPtr()[k];
        if (i > j) {
          const int a = at(p, i), b = at(p, j);
          at(up_row, at(next, std::max(a, b))++) = std::min(a, b);
        }
      }
  };

  // 2. Elimination tree of the ordered matrix (Liu 1990: ancestors with path compression).
  std::vector<int> parent(N, -1), work(N);
  auto etree = [&]() {
    std::vector<int>& anc = work;
    for (int k = 0; k < n; ++k) {
      at(parent, k) = -1;
      at(anc, k) = -1;
      for (Index q = at(up_ptr, k); q < at(up_ptr, k + 1); ++q)
        for (int i = at(up_row, q); i != -1 && i < k;) {  // climb from i to the root of its subtree, point it at k
          const int next = at(anc, i);
          at(anc, i) = k;
          if (next == -1) at(parent, i) = k;
          i = next;
        }
    }
  };
  std::vector<Index> lo_ptr(N + 1, 0);
  std::vector<int> lo_row, cc(N, 0);
  // Steps 2 to 4 for the ordering p0: perm_, parent, the lower pattern and the column counts cc.
  auto symbolic = [&](const std::vector<int>& p0) {
  upper_pattern(p0);
  etree();

  // 3. Postorder of the tree (children in ascending order), composed with AMD: supernodes become
  // ranges of columns, and the tree of the final order is the relabelled one.
  std::vector<int> post_of(N);  // position in p0 -> postorder position
  {
    std::vector<int> head(N, -1), next(N, -1), stack;
    stack.reserve(N);
    for (int j = n - 1; j >= 0; --j)
      if (at(parent, j) != -1) {
        at(next, j) = at(head, at(parent, j));
        at(head, at(parent, j)) = j;
      }
    int k = 0;
    for (int r = 0; r < n; ++r) {
      if (at(parent, r) != -1) continue;
      stack.push_back(r);
      while (!stack.empty()) {
        const int p = stack.back(), c = at(head, p);
        if (c == -1) {
          stack.pop_back();
          at(post_of, p) = k++;
        } else {
          at(head, p) = at(next, c);
          stack.push_back(c);
        }
      }
    }
    std::vector<int> relabelled(N);
    for (int j = 0; j < n; ++j) at(relabelled, at(post_of, j)) = at(parent, j) == -1 ? -1 : at(post_of, at(parent, j));
    parent.swap(relabelled);
  }
  perm_.resize(N);
  for (int i = 0; i < n; ++i) at(perm_, i) = at(post_of, at(p0, i));

  // The strictly lower pattern of P A P^T by columns, and, for every stored entry of A's lower
  // triangle, its (row, column) there.
  std::fill(lo_ptr.begin(), lo_ptr.end(), 0);
  for (int j = 0; j < n; ++j)
    for (Index k = first(j); k < last(j); ++k) {
      const int i = A.innerIndexPtr()[k];
      if (i > j) ++at(lo_ptr, std::min(at(perm_, i), at(perm_, j)) + 1);
    }
  for (int j = 0; j < n; ++j) at(lo_ptr, j + 1) += at(lo_ptr, j);
  lo_row.resize(static_cast<size_t>(lo_ptr[N]));
  {
    std::vector<Index> next(lo_ptr.begin(), lo_ptr.end() - 1);
    for (int j = 0; j < n; ++j)
      for (Index k = first(j); k < last(j); ++k) {
        const int i = A.innerIndexPtr()[k];
        if (i > j) {
          const int a = at(perm_, i), b = at(perm_, j);
          at(lo_row, at(next, std::min(a, b))++) = std::max(a, b);
        }
      }
  }

  // 4. Column counts of L (Gilbert, Ng & Peyton 1994; Davis 2006, sec. 4.5). In postorder (the
  // identity now), A(i, j) with i > j belongs to the skeleton when j is a leaf of row i's subtree,
  // which is when first(j), the first descendant of j, is past the previous leaf's; each leaf adds 1 to
  // its column, each next leaf subtracts 1 at the least common ancestor with the previous one, and a
  // column's count is the sum over its subtree.
  {
    std::vector<int> firstdesc(N, -1), maxfirst(N, -1), prevleaf(N, -1), anc(N);
    std::vector<int>& delta = cc;
    for (int k = 0; k < n; ++k) {
      at(delta, k) = at(firstdesc, k) == -1 ? 1 : 0;  // a leaf has no descendant before it
      for (int j = k; j != -1 && at(firstdesc, j) == -1; j = at(parent, j)) at(firstdesc, j) = k;
    }
    std::iota(anc.begin(), anc.end(), 0);
    for (int j = 0; j < n; ++j) {
      if (at(parent, j) != -1) --at(delta, at(parent, j));
      for (Index q = at(lo_ptr, j); q < at(lo_ptr, j + 1); ++q) {
        const int i = at(lo_row, q);
        if (at(firstdesc, j) <= at(maxfirst, i)) continue;  // j is not a leaf of row i's subtree
        at(maxfirst, i) = at(firstdesc, j);
        const int jprev = at(prevleaf, i);
        at(prevleaf, i) = j;
        ++at(delta, j);
        if (jprev != -1) {  // the least common ancestor of j and the previous leaf: the root of jprev's set
          int q2 = jprev;
          while (at(anc, q2) != q2) q2 = at(anc, q2);
          for (int s = jprev; s != q2;) {  // path compression
            const int up = at(anc, s);
            at(anc, s) = q2;
            s = up;
          }
          --at(delta, q2);
        }
      }
      if (at(parent, j) != -1) at(anc, j) = at(parent, j);
    }
    for (int j = 0; j < n; ++j)
      if (at(parent, j) != -1) at(cc, at(parent, j)) += at(cc, j);
  }
  nnz_exact_ = 0;
  flops_exact_ = 0.0;
  for (int j = 0; j < n; ++j) {
    nnz_exact_ += at(cc, j);
    flops_exact_ += static_cast<double>(at(cc, j)) * at(cc, j);
  }
  return flops_exact_;
  };
  if (ordering_reused_) {
    symbolic(kept);
    used_ = kept_used;
  } else if (ordering == SupernodalOrdering::amd) {
    symbolic(amd);
    used_ = SupernodalOrdering::amd;
  } else if (ordering == SupernodalOrdering::nested_dissection) {
    symbolic(nd);
    used_ = SupernodalOrdering::nested_dissection;
  } else {
    // Nested dissection only where AMD's factor has large fronts (its columns average 32 entries or
    // more): on chains and bands it cannot do better and costs more than the rest of the analysis.
    // It is kept where it saves a clear share of both costs: a fifth of the factorisation's flops and
    // a twentieth of the factor's entries, which every solve reads. On 3-D meshes it saves far more
    // (a 12 x 12 x 12 block of bricks: 4x fewer flops, 1.9x fewer entries); on 2-D meshes the two
    // orderings are close, and where nested dissection's gain was a few per cent of the flops its
    // relaxed supernodes stored more entries than AMD's (solves up to 12 % slower) after an analysis
    // 3 to 7 times as long (benchmarks/fe_newton.py's walls).
    const double f_amd = symbolic(amd);
    const Index nnz_amd = nnz_exact_;
    used_ = SupernodalOrdering::amd;
    if (f_amd >= 32.0 * static_cast<double>(nnz_amd)) {
      supernodal_detail::nested_dissection(A, nd);
      used_ = SupernodalOrdering::nested_dissection;
      const double f_nd = symbolic(nd);
      if (!(f_nd <= kNestedDissectionFlops * f_amd &&
            static_cast<double>(nnz_exact_) <= kNestedDissectionEntries * static_cast<double>(nnz_amd)))
        symbolic(amd), used_ = SupernodalOrdering::amd;
    }
  }
  if (cached && !ordering_reused_) {
    supernodal_detail::OrderingCache::Item item;
    item.key = key, item.used = used_;
    item.order = used_ == SupernodalOrdering::nested_dissection ? std::move(nd) : std::move(amd);
    supernodal_detail::ordering_cache().insert(std::move(item));
  }

  // 5. Fundamental supernodes: j+1 continues j's supernode when it is j's parent, j is its only child,
  // and its column has j's structure less the diagonal.
  std::vector<int> fstart;  // first column of each fundamental supernode, then n
  {
    std::vector<int> nchild(N, 0);
    for (int j = 0; j < n; ++j)
      if (at(parent, j) != -1) ++at(nchild, at(parent, j));
    for (int j = 0; j < n; ++j)
      if (j == 0 || !(at(parent, j - 1) == j && at(nchild, j) == 1 && at(cc, j - 1) == at(cc, j) + 1))
        fstart.push_back(j);
    fstart.push_back(n);
  }
  const int nf = static_cast<int>(fstart.size()) - 1;
  std::vector<int> fsuper(N);  // column -> fundamental supernode
  for (int f = 0; f < nf; ++f)
    for (int j = at(fstart, f); j < at(fstart, f + 1); ++j) at(fsuper, j) = f;

  // 6. Relaxed amalgamation (Ashcraft & Grimes 1989; CHOLMOD's rule), from the root down: a supernode
  // merges into its parent's group when that group begins right after its last column. The merged
  // rows are its columns plus the group's rows (the child's structure is in the group's), so the new
  // zeros are (child columns) x (merged rows - child rows).
  std::vector<int> grp(static_cast<size_t>(nf));  // union-find: the first fundamental supernode of the group
  std::vector<Index> gcols(static_cast<size_t>(nf)), grows(static_cast<size_t>(nf));
  std::vector<double> gzeros(static_cast<size_t>(nf), 0.0);
  for (int f = 0; f < nf; ++f) {
    at(grp, f) = f;
    at(gcols, f) = at(fstart, f + 1) - at(fstart, f);
    at(grows, f) = at(cc, at(fstart, f));
  }
  auto find = [&](int f) {
    int r = f;
    while (at(grp, r) != r) r = at(grp, r);
    while (at(grp, f) != r) {
      const int up = at(grp, f);
      at(grp, f) = r;
      f = up;
    }
    return r;
  };
  const SupernodeRelaxation& rx = relaxation;
  for (int j = nf - 2; j >= 0; --j) {
    const int pcol = at(parent, at(fstart, j + 1) - 1);
    if (pcol == -1) continue;
    const int g = find(at(fsuper, pcol));
    if (g != j + 1) continue;  // the parent's group does not begin right after j
    const Index cols = at(gcols, j) + at(gcols, g), rows = at(gcols, j) + at(grows, g);
    const double zeros = at(gzeros, j) + at(gzeros, g) +
                         static_cast<double>(at(gcols, j)) * static_cast<double>(rows - at(grows, j));
    const double dc = static_cast<double>(cols), stored = dc * static_cast<double>(rows) - 0.5 * dc * (dc - 1.0);
    const double z = zeros / stored;
    const bool merge = cols <= rx.always || (cols <= rx.small && z < rx.small_zeros) ||
                       (cols <= rx.medium && z < rx.medium_zeros) || z < rx.large_zeros;
    if (!merge) continue;
    at(grp, g) = j;
    at(gcols, j) = cols;
    at(grows, j) = rows;
    at(gzeros, j) = zeros;
  }
  super_start_.clear();
  for (int f = 0; f < nf; ++f)
    if (at(grp, f) == f) super_start_.push_back(at(fstart, f));
  super_start_.push_back(n);
  const int ns = static_cast<int>(super_start_.size()) - 1;
  nsuper_ = ns;
  super_of_.resize(N);
  for (int s = 0; s < ns; ++s)
    for (int j = at(super_start_, s); j < at(super_start_, s + 1); ++j) at(super_of_, j) = s;

  // 7. Row structure of each supernode: its columns, the rows of A's columns in it, and the rows of its
  // children past its first column (the symbolic factorisation by supernodes), sorted.
  std::vector<int> shead(static_cast<size_t>(ns), -1), snext(static_cast<size_t>(ns), -1);
  for (int s = ns - 1; s >= 0; --s) {
    const int pcol = at(parent, at(super_start_, s + 1) - 1);
    if (pcol != -1) {
      const int sp = at(super_of_, pcol);
      at(snext, s) = at(shead, sp);
      at(shead, sp) = s;
    }
  }
  row_ptr_.assign(static_cast<size_t>(ns) + 1, 0);
  rows_.clear();
  rows_.reserve(static_cast<size_t>(nnz_exact_ / 2 + n));
  {
    std::vector<int>& mark = work;
    std::fill(mark.begin(), mark.end(), -1);
    for (int s = 0; s < ns; ++s) {
      const int k1 = at(super_start_, s), k2 = at(super_start_, s + 1);
      for (int c = k1; c < k2; ++c) {
        rows_.push_back(c);
        at(mark, c) = s;
      }
      const size_t tail = rows_.size();
      auto add = [&](int r) {
        if (r >= k2 && at(mark, r) != s) {
          at(mark, r) = s;
          rows_.push_back(r);
        }
      };
      for (int c = k1; c < k2; ++c)
        for (Index q = at(lo_ptr, c); q < at(lo_ptr, c + 1); ++q) add(at(lo_row, q));
      for (int ch = at(shead, s); ch != -1; ch = at(snext, ch)) {
        const Index nch = at(super_start_, ch + 1) - at(super_start_, ch);
        for (Index q = at(row_ptr_, ch) + nch; q < at(row_ptr_, ch + 1); ++q) add(at(rows_, q));
      }
      std::sort(rows_.begin() + static_cast<std::ptrdiff_t>(tail), rows_.end());
      at(row_ptr_, s + 1) = static_cast<Index>(rows_.size());
    }
  }
  rows_.shrink_to_fit();

  // 8. Panels, sizes and counts.
  val_ptr_.assign(static_cast<size_t>(ns) + 1, 0);
  nnz_ = 0;
  flops_ = 0.0;
  Index max_rows = 0, max_wbuf = 0;
  for (int s = 0; s < ns; ++s) {
    const Index nc = at(super_start_, s + 1) - at(super_start_, s), nr = at(row_ptr_, s + 1) - at(row_ptr_, s);
    at(val_ptr_, s + 1) = at(val_ptr_, s) + nr * nc;
    nnz_ += nr * nc - nc * (nc - 1) / 2;
    for (Index k = 0; k < nc; ++k) flops_ += static_cast<double>(nr - k) * static_cast<double>(nr - k);
    max_rows = std::max(max_rows, nr);
    constexpr Index pb = supernodal_detail::kPanelBlock;
    if (nc > supernodal_detail::kScalarPanel) max_wbuf = std::max(max_wbuf, (nr - std::min(nc, pb)) * pb);
  }
  values_.assign(static_cast<size_t>(at(val_ptr_, ns)), 0.0);

  // 9. Where each stored value of A's lower triangle goes: its supernode's panel, at (local row, column).
  asm_ptr_.assign(static_cast<size_t>(ns) + 1, 0);
  for (int j = 0; j < n; ++j)
    for (Index k = first(j); k < last(j); ++k)
      if (A.innerIndexPtr()[k] >= j)
        ++at(asm_ptr_, at(super_of_, std::min(at(perm_, A.innerIndexPtr()[k]), at(perm_, j))) + 1);
  for (int s = 0; s < ns; ++s) at(asm_ptr_, s + 1) += at(asm_ptr_, s);
  asm_src_.resize(static_cast<size_t>(at(asm_ptr_, ns)));
  asm_dst_.resize(asm_src_.size());
  {
    std::vector<Index> next(asm_ptr_.begin(), asm_ptr_.end() - 1);
    for (int j = 0; j < n; ++j)
      for (Index k = first(j); k < last(j); ++k) {
        const int i = A.innerIndexPtr()[k];
        if (i < j) continue;
        const int a = at(perm_, i), b = at(perm_, j), r = std::max(a, b), c = std::min(a, b);
        const int s = at(super_of_, c);
        const int* rs = rows_.data() + at(row_ptr_, s);
        const Index nr = at(row_ptr_, s + 1) - at(row_ptr_, s);
        const Index local = std::lower_bound(rs, rs + nr, r) - rs;
        const Index slot = at(next, s)++;
        at(asm_src_, slot) = k;
        at(asm_dst_, slot) = (c - at(super_start_, s)) * nr + local;
      }
  }

  // 10. The update schedule: descendant d's rows past its columns fall in groups, each in the columns
  // of one ancestor s (ascending); the group from p to p1 updates s's columns, the rows from p to d's
  // end update s's rows. Recorded by target, with the largest dense product for the workspace.
  upd_ptr_.assign(static_cast<size_t>(ns) + 1, 0);
  Index max_c = 0, max_w = 0;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<Index> next;
    if (pass == 1) {
      for (int s = 0; s < ns; ++s) at(upd_ptr_, s + 1) += at(upd_ptr_, s);
      upd_d_.resize(static_cast<size_t>(at(upd_ptr_, ns)));
      upd_p_.resize(upd_d_.size());
      upd_p1_.resize(upd_d_.size());
      next.assign(upd_ptr_.begin(), upd_ptr_.end() - 1);
    }
    for (int d = 0; d < ns; ++d) {
      const Index ncd = at(super_start_, d + 1) - at(super_start_, d);
      const int* rs = rows_.data() + at(row_ptr_, d);
      const Index nrd = at(row_ptr_, d + 1) - at(row_ptr_, d);
      for (Index p = ncd; p < nrd;) {
        const int s = at(super_of_, rs[p]);
        const int k2 = at(super_start_, s + 1);
        Index p1 = p;
        while (p1 < nrd && rs[p1] < k2) ++p1;
        if (pass == 0) {
          ++at(upd_ptr_, s + 1);
          const Index m1 = p1 - p, m2 = nrd - p;
          max_c = std::max(max_c, m1 * m2);
          max_w = std::max(max_w, m1 * ncd);
        } else {
          const Index slot = at(next, s)++;
          at(upd_d_, slot) = d;
          at(upd_p_, slot) = static_cast<int>(p);
          at(upd_p1_, slot) = static_cast<int>(p1);
        }
        p = p1;
      }
    }
  }

  // 11. Workspaces of the numeric phase.
  map_.assign(N, 0);
  rel_.assign(static_cast<size_t>(max_rows), 0);
  cbuf_.assign(static_cast<size_t>(max_c), 0.0);
  wbuf_.assign(LDLT ? static_cast<size_t>(std::max(max_w, max_wbuf)) : 0, 0.0);
  D_.setZero(n);
}

// ---------------------------------------------------------------------------------------------------
// Numeric factorisation.
// ---------------------------------------------------------------------------------------------------

// Ls (supernode s's panel) -= L_d(p:, :) [D_d] L_d(p:p1, :)^T, scattered to s's local rows (map_) and
// columns (row - first column of s).
template <bool LDLT>
void SupernodalCholesky<LDLT>::update_from(Index d, Index p, Index p1, Index s, double* Ls) {
  const Index k1 = super_start_[static_cast<size_t>(s)];
  const Index nr = row_ptr_[static_cast<size_t>(s) + 1] - row_ptr_[static_cast<size_t>(s)];
  const Index ncd = super_start_[static_cast<size_t>(d) + 1] - super_start_[static_cast<size_t>(d)];
  const Index nrd = row_ptr_[static_cast<size_t>(d) + 1] - row_ptr_[static_cast<size_t>(d)];
  const int* drows = rows_.data() + row_ptr_[static_cast<size_t>(d)];
  const double* Ld = values_.data() + val_ptr_[static_cast<size_t>(d)];
  const Index m1 = p1 - p, m2 = nrd - p;
  int* rel = rel_.data();
  for (Index i = 0; i < m2; ++i) rel[i] = map_[static_cast<size_t>(drows[p + i])];

  if (m1 * m2 * ncd <= supernodal_detail::kScalarUpdate) {
    // Small: column by column of the target, each a sum of ncd scaled columns of d, scattered.
    for (Index jj = 0; jj < m1; ++jj) {
      double* tcol = Ls + (drows[p + jj] - k1) * nr;
      for (Index k = 0; k < ncd; ++k) {
        const double* dk = Ld + k * nrd + p;
        double f = dk[jj];
        if constexpr (LDLT) f *= Ld[k * nrd + k];
        if (f == 0.0) continue;
        for (Index ii = jj; ii < m2; ++ii) tcol[rel[ii]] -= dk[ii] * f;
      }
    }
    return;
  }

  const double* R1 = Ld + p;  // rows p ... (m2 of them), ncd columns, leading dimension nrd
  const double* W = R1;       // the right factor: R1's first m1 rows, scaled by D for LDL^T
  Index ldw = nrd;
  if constexpr (LDLT) {
    double* w = wbuf_.data();
    for (Index k = 0; k < ncd; ++k) {
      const double dk = Ld[k * nrd + k];
      for (Index jj = 0; jj < m1; ++jj) w[k * m1 + jj] = R1[k * nrd + jj] * dk;
    }
    W = w;
    ldw = m1;
  }
  // Contiguous in s (rows and columns): the product goes straight into the panel (the strict upper
  // triangle of the top block lands in the unused upper triangle of s's diagonal block).
  const bool contiguous = rel[m2 - 1] - rel[0] == m2 - 1 && drows[p1 - 1] - drows[p] == m1 - 1;
  // By blocks of kUpdateBlock columns, each from its diagonal down: the strict upper part of the top
  // m1 x m1 square, which is not needed, is computed only within the diagonal blocks.
  constexpr Index bw = supernodal_detail::kUpdateBlock;
  if (contiguous) {
    double* target = Ls + (drows[p] - k1) * nr + rel[0];
    for (Index j0 = 0; j0 < m1; j0 += bw)
      supernodal_detail::gemm_nt_sub(m2 - j0, std::min(bw, m1 - j0), ncd, R1 + j0, nrd, W + j0, ldw,
                                     target + j0 * nr + j0, nr);
    return;
  }
  double* C = cbuf_.data();  // m2 x m1
  for (Index j0 = 0; j0 < m1; j0 += bw) {
    const Index jb = std::min(bw, m1 - j0);
    for (Index j = j0; j < j0 + jb; ++j) std::fill(C + j * m2 + j0, C + (j + 1) * m2, 0.0);
    supernodal_detail::gemm_nt_sub(m2 - j0, jb, ncd, R1 + j0, nrd, W + j0, ldw, C + j0 * m2 + j0, m2);
  }
  for (Index jj = 0; jj < m1; ++jj) {  // C holds -(the update); its lower part is added into place
    double* tcol = Ls + (drows[p + jj] - k1) * nr;
    const double* ccol = C + jj * m2;
    for (Index ii = jj; ii < m2; ++ii) tcol[rel[ii]] += ccol[ii];
  }
}

// Blocked right-looking dense factorisation of one supernode's panel (nr x nc, nr >= nc): the diagonal
// block by the scalar kernel, the rows below by TRSM, the trailing columns by GEMM in blocks of
// columns (so the strict upper part computed in vain is one block's).
template <bool LDLT>
bool SupernodalCholesky<LDLT>::factor_panel(double* L, Index nr, Index nc) {
  using namespace supernodal_detail;
  if (nc <= kScalarPanel) return panel_scalar<LDLT>(L, nr, nc, nr) < 0;
  for (Index j0 = 0; j0 < nc; j0 += kPanelBlock) {
    const Index jb = std::min(kPanelBlock, nc - j0), j1 = j0 + jb, mb = nr - j1;
    double* Ajj = L + j0 * nr + j0;
    if (panel_scalar<LDLT>(Ajj, jb, jb, nr) >= 0) return false;
    if (mb == 0) continue;
    double* B = Ajj + jb;  // rows j1 ..., columns j0 ... j1-1
    trsm_right_lower_t<LDLT>(mb, jb, Ajj, nr, B, nr);
    const double* right = B;  // the trailing update is B D B^T (LDL^T) or B B^T
    Index ldr = nr;
    if constexpr (LDLT) {  // B is L21 D here: keep it, then divide by D
      double* w = wbuf_.data();
      for (Index k = 0; k < jb; ++k) {
        double* bk = B + k * nr;
        std::copy(bk, bk + mb, w + k * mb);
        const double inv = 1.0 / Ajj[k * nr + k];
        for (Index i = 0; i < mb; ++i) bk[i] *= inv;
      }
      right = w;
      ldr = mb;
    }
    for (Index c0 = j1; c0 < nc; c0 += kUpdateBlock) {
      const Index cb = std::min(kUpdateBlock, nc - c0);
      gemm_nt_sub(nr - c0, cb, jb, B + (c0 - j1), nr, right + (c0 - j1), ldr, L + c0 * nr + c0, nr);
    }
  }
  return true;
}

template <bool LDLT>
void SupernodalCholesky<LDLT>::factorize_values(const SparseMatrix& A) {
  info_ = Eigen::Success;
  const double* a = A.valuePtr();
  for (Index s = 0; s < nsuper_; ++s) {
    const size_t su = static_cast<size_t>(s);
    const Index nc = super_start_[su + 1] - super_start_[su];
    const Index nr = row_ptr_[su + 1] - row_ptr_[su];
    const int* rs = rows_.data() + row_ptr_[su];
    double* Ls = values_.data() + val_ptr_[su];
    for (Index i = 0; i < nr; ++i) map_[static_cast<size_t>(rs[i])] = static_cast<int>(i);
    std::fill(Ls, Ls + nr * nc, 0.0);
    for (Index k = asm_ptr_[su]; k < asm_ptr_[su + 1]; ++k)
      Ls[asm_dst_[static_cast<size_t>(k)]] = a[asm_src_[static_cast<size_t>(k)]];
    for (Index u = upd_ptr_[su]; u < upd_ptr_[su + 1]; ++u) {
      const size_t uu = static_cast<size_t>(u);
      update_from(upd_d_[uu], upd_p_[uu], upd_p1_[uu], s, Ls);
    }
    if (!factor_panel(Ls, nr, nc)) {
      info_ = Eigen::NumericalIssue;
      return;
    }
    const Index k1 = super_start_[su];
    for (Index k = 0; k < nc; ++k) {  // the pivots, while the panel is in cache
      const double v = Ls[k * nr + k];
      D_[k1 + k] = LDLT ? v : v * v;
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// Solve: forward and backward substitution by supernodes.
// ---------------------------------------------------------------------------------------------------

template <bool LDLT>
void SupernodalCholesky<LDLT>::solve_in_place(double* x, Vector& work) const {
  using namespace supernodal_detail;
  const Index n = n_;
  double* w = work.data();
  for (Index i = 0; i < n; ++i) w[perm_[static_cast<size_t>(i)]] = x[i];
  double* t = x;  // x is free until the end: the scratch of the off-diagonal products
  // L y = b.
  for (Index s = 0; s < nsuper_; ++s) {
    const size_t su = static_cast<size_t>(s);
    const Index k1 = super_start_[su], nc = super_start_[su + 1] - k1, nr = row_ptr_[su + 1] - row_ptr_[su];
    const int* rs = rows_.data() + row_ptr_[su];
    const double* L = values_.data() + val_ptr_[su];
    double* x1 = w + k1;
    if (nc <= kScalarSolve) {
      solve_small<LDLT, true>(nc, L, nr, rs, x1, w);
      continue;
    }
    const ConstPanel L11(L, nc, nc, Eigen::OuterStride<>(nr));
    VecMap xm(x1, nc);
    if constexpr (LDLT)
      L11.triangularView<Eigen::UnitLower>().solveInPlace(xm);
    else
      L11.triangularView<Eigen::Lower>().solveInPlace(xm);
    if (nr > nc) {
      VecMap tm(t, nr - nc);
      tm.noalias() = ConstPanel(L + nc, nr - nc, nc, Eigen::OuterStride<>(nr)) * xm;
      for (Index i = nc; i < nr; ++i) w[rs[i]] -= t[i - nc];
    }
  }
  if constexpr (LDLT)
    for (Index i = 0; i < n; ++i) w[i] /= D_[i];
  // L^T x = y.
  for (Index s = nsuper_ - 1; s >= 0; --s) {
    const size_t su = static_cast<size_t>(s);
    const Index k1 = super_start_[su], nc = super_start_[su + 1] - k1, nr = row_ptr_[su + 1] - row_ptr_[su];
    const int* rs = rows_.data() + row_ptr_[su];
    const double* L = values_.data() + val_ptr_[su];
    double* x1 = w + k1;
    if (nc <= kScalarSolve) {
      solve_small<LDLT, false>(nc, L, nr, rs, x1, w);
      continue;
    }
    const ConstPanel L11(L, nc, nc, Eigen::OuterStride<>(nr));
    VecMap xm(x1, nc);
    if (nr > nc) {
      for (Index i = nc; i < nr; ++i) t[i - nc] = w[rs[i]];
      xm.noalias() -= ConstPanel(L + nc, nr - nc, nc, Eigen::OuterStride<>(nr)).transpose() * VecMap(t, nr - nc);
    }
    if constexpr (LDLT)
      L11.transpose().triangularView<Eigen::UnitUpper>().solveInPlace(xm);
    else
      L11.transpose().triangularView<Eigen::Upper>().solveInPlace(xm);
  }
  for (Index i = 0; i < n; ++i) x[i] = w[perm_[static_cast<size_t>(i)]];
}

template <bool LDLT>
SparseMatrix SupernodalCholesky<LDLT>::matrix_l() const {
  std::vector<Eigen::Triplet<double, int>> t;
  for (Index s = 0; s < nsuper_; ++s) {
    const size_t su = static_cast<size_t>(s);
    const Index k1 = super_start_[su], nc = super_start_[su + 1] - k1, nr = row_ptr_[su + 1] - row_ptr_[su];
    const int* rs = rows_.data() + row_ptr_[su];
    const double* L = values_.data() + val_ptr_[su];
    for (Index k = 0; k < nc; ++k) {
      t.emplace_back(static_cast<int>(k1 + k), static_cast<int>(k1 + k), LDLT ? 1.0 : L[k * nr + k]);
      for (Index i = k + 1; i < nr; ++i)
        if (L[k * nr + i] != 0.0) t.emplace_back(rs[i], static_cast<int>(k1 + k), L[k * nr + i]);
    }
  }
  SparseMatrix out(n_, n_);
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

}  // namespace nvib
