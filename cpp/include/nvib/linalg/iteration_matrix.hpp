// The iteration matrix an implicit step asks its linear solver for.
#pragma once

#include "../core/types.hpp"

namespace nvib {

// S = cM M + cC C_t + cK K_t with the tangents taken at (u, v, t).
struct IterationMatrix {
  double cM = 0.0, cC = 0.0, cK = 1.0;
  const Vector* u = nullptr;
  const Vector* v = nullptr;
  double t = 0.0;
};

// Which linear solver the Newton component uses: automatic (a dense LU for small or nearly full
// iteration matrices, sparse otherwise: AutoLinearSolver), or forced.
enum class LinearSolverChoice { automatic, dense, sparse };
inline const char* to_string(LinearSolverChoice c) {
  return c == LinearSolverChoice::automatic ? "auto" : c == LinearSolverChoice::dense ? "dense" : "sparse";
}

}  // namespace nvib
