// Hints to the compiler about the per-step code (no effect on results).
#pragma once

// NVIB_FLATTEN: every call inside the function is inlined into it (loops.hpp: a loop body used in
// many loops, which the inliner would otherwise call entry by entry).
// NVIB_NOINLINE: a rarely taken or large path kept out of the per-step code it is called from, so
// that the step around it stays within the inliner's budget.
#if defined(__GNUC__)
#define NVIB_FLATTEN __attribute__((flatten))
#define NVIB_NOINLINE __attribute__((noinline))
#else
#define NVIB_FLATTEN
#define NVIB_NOINLINE
#endif
