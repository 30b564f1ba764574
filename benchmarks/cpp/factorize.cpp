// Sparse symmetric factorisations of one matrix, timed: nvib's simplicial OrderedCholesky (LDL^T and
// LL^T, AMD then Eigen's simplicial factorisation) against SupernodalCholesky (LL^T and LDL^T).
// Reads a Matrix Market file (coordinate real symmetric: the lower triangle, 1-based), and prints
// one JSON line per method: the best time of analyze(), factorize_values() and one solve_in_place()
// over the repeats, nnz(L), the flop count, the ordering, the relative residual |A x - b| / (|A| |x|).
//   factorize MATRIX.mtx [--repeats R] [--methods a,b,...] [--budget SECONDS]
//                        [--relax always,small,small_zeros,medium,medium_zeros,large_zeros]
// Methods: simplicial_ldlt, simplicial_llt, supernodal_llt_amd (AMD forced, the simplicial one's
// order), supernodal_llt, supernodal_ldlt. A method whose factorisation takes longer than the budget
// (default 20 s) is repeated no more.
#include <nvib/linalg/sparse_cholesky.hpp>
#include <nvib/linalg/supernodal_cholesky.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

using nvib::Index;
using nvib::SparseMatrix;
using nvib::Vector;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The lower triangle of a symmetric Matrix Market file (entries above the diagonal are mirrored).
SparseMatrix read_market(const char* path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", path);
    std::exit(2);
  }
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const char* p = text.c_str();
  if (std::strncmp(p, "%%MatrixMarket", 14) != 0 || !std::strstr(p, "symmetric")) {
    std::fprintf(stderr, "%s: not a symmetric Matrix Market file\n", path);
    std::exit(2);
  }
  while (*p == '%')
    while (*p && *p++ != '\n') {
    }
  char* end;
  const long rows = std::strtol(p, &end, 10);
  const long cols = std::strtol(end, &end, 10);
  const long nnz = std::strtol(end, &end, 10);
  p = end;
  if (rows != cols) {
    std::fprintf(stderr, "%s: not square\n", path);
    std::exit(2);
  }
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(static_cast<size_t>(nnz));
  for (long k = 0; k < nnz; ++k) {
    const int i = static_cast<int>(std::strtol(p, &end, 10)) - 1;
    const int j = static_cast<int>(std::strtol(end, &end, 10)) - 1;
    const double v = std::strtod(end, &end);
    p = end;
    t.emplace_back(std::max(i, j), std::min(i, j), v);
  }
  SparseMatrix A(rows, rows);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

struct Options {
  int repeats = 3;
  double budget = 20.0;
  std::vector<std::string> methods = {"simplicial_ldlt", "simplicial_llt", "supernodal_llt_amd", "supernodal_llt",
                                      "supernodal_ldlt"};
  bool relax_given = false;
  nvib::SupernodeRelaxation relax;
};

template <class F>
void time_method(const char* name, const SparseMatrix& A, const SparseMatrix& full, const Options& o, F&& make) {
  const Index n = A.rows();
  Vector b(n);
  for (Index i = 0; i < n; ++i) b[i] = std::sin(0.37 * static_cast<double>(i) + 1.0);
  double t_an = 1e300, t_fa = 1e300, t_so = 1e300, res = 0.0;
  long nnz = 0;
  double flops = 0.0, flops_exact = 0.0;
  long nnz_exact = 0;
  int supernodes = 0;
  const char* ordering = "AMD";
  bool ok = true;
  for (int r = 0; r < o.repeats; ++r) {
    auto f = make();
    nvib::supernodal_detail::ordering_cache().clear();  // a cold analysis each time, not the ordering kept from the last
    double t0 = now();
    f->analyze(A);
    t_an = std::min(t_an, now() - t0);
    t0 = now();
    f->factorize_values(A);
    const double tf = now() - t0;
    t_fa = std::min(t_fa, tf);
    if (f->info() != Eigen::Success) {
      ok = false;
      break;
    }
    Vector work(n), x = b;
    for (int s = 0; s < 5; ++s) {  // the solve: best of 5 in each repeat
      x = b;
      t0 = now();
      f->solve_in_place(x.data(), work);
      t_so = std::min(t_so, now() - t0);
    }
    res = (full * x - b).norm() / (full.norm() * x.norm());
    if constexpr (std::is_same_v<std::decay_t<decltype(*f)>, nvib::SupernodalCholesky<true>> ||
                  std::is_same_v<std::decay_t<decltype(*f)>, nvib::SupernodalCholesky<false>>) {
      nnz = static_cast<long>(f->nonzeros());
      flops = f->flops();
      nnz_exact = static_cast<long>(f->simplicial_nonzeros());
      flops_exact = f->simplicial_flops();
      supernodes = static_cast<int>(f->supernodes());
      ordering = f->ordering_used() == nvib::SupernodalOrdering::amd ? "AMD" : "nested dissection";
    } else {  // the same AMD order (the postorder changes no count): its flops from the column counts
      nnz = static_cast<long>(f->matrixL().nestedExpression().nonZeros()) +
            (std::is_same_v<std::decay_t<decltype(*f)>, nvib::OrderedCholesky<true>> ? static_cast<long>(n) : 0L);
      nnz_exact = nnz;
      if (r == 0) {
        nvib::SupernodalCholesky<false> counts;
        counts.ordering = nvib::SupernodalOrdering::amd;
        counts.analyze(A);
        flops = flops_exact = counts.simplicial_flops();
      }
    }
    if (tf > o.budget) break;
  }
  std::printf(
      "{\"method\": \"%s\", \"n\": %ld, \"nnz_a\": %ld, \"ok\": %s, \"analyze\": %.6g, \"factorize\": %.6g, "
      "\"solve\": %.6g, \"residual\": %.3g, \"nnz_l\": %ld, \"nnz_l_exact\": %ld, \"flops\": %.6g, "
      "\"flops_exact\": %.6g, \"supernodes\": %d, \"ordering\": \"%s\"}\n",
      name, static_cast<long>(n), static_cast<long>(A.nonZeros()), ok ? "true" : "false", t_an, t_fa, t_so, res, nnz,
      nnz_exact, flops, flops_exact, supernodes, ordering);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s MATRIX.mtx [--repeats R] [--methods a,b] [--budget S] [--relax a,s,zs,m,zm,zl]\n",
                 argv[0]);
    return 2;
  }
  Options o;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : "";
    if (a == "--repeats") {
      o.repeats = std::atoi(v), ++i;
    } else if (a == "--budget") {
      o.budget = std::atof(v), ++i;
    } else if (a == "--methods") {
      o.methods.clear();
      std::stringstream s(v);
      std::string m;
      while (std::getline(s, m, ',')) o.methods.push_back(m);
      ++i;
    } else if (a == "--relax") {
      nvib::SupernodeRelaxation& r = o.relax;
      if (std::sscanf(v, "%d,%d,%lf,%d,%lf,%lf", &r.always, &r.small, &r.small_zeros, &r.medium, &r.medium_zeros,
                      &r.large_zeros) != 6) {
        std::fprintf(stderr, "--relax wants six numbers\n");
        return 2;
      }
      o.relax_given = true;
      ++i;
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const SparseMatrix A = read_market(argv[1]);
  SparseMatrix full(A.rows(), A.cols());
  full = A.selfadjointView<Eigen::Lower>();
  for (const std::string& m : o.methods) {
    if (m == "simplicial_ldlt") {
      time_method(m.c_str(), A, full, o, [] { return std::make_unique<nvib::OrderedCholesky<true>>(); });
    } else if (m == "simplicial_llt") {
      time_method(m.c_str(), A, full, o, [] { return std::make_unique<nvib::OrderedCholesky<false>>(); });
    } else if (m == "supernodal_llt") {
      time_method(m.c_str(), A, full, o, [&] {
        auto f = std::make_unique<nvib::SupernodalCholesky<false>>();
        if (o.relax_given) f->relaxation = o.relax;
        return f;
      });
    } else if (m == "supernodal_llt_amd") {  // the ordering of the simplicial one: the kernels' share
      time_method(m.c_str(), A, full, o, [&] {
        auto f = std::make_unique<nvib::SupernodalCholesky<false>>();
        if (o.relax_given) f->relaxation = o.relax;
        f->ordering = nvib::SupernodalOrdering::amd;
        return f;
      });
    } else if (m == "supernodal_ldlt") {
      time_method(m.c_str(), A, full, o, [&] {
        auto f = std::make_unique<nvib::SupernodalCholesky<true>>();
        if (o.relax_given) f->relaxation = o.relax;
        return f;
      });
    } else {
      std::fprintf(stderr, "unknown method %s\n", m.c_str());
      return 2;
    }
  }
  return 0;
}
