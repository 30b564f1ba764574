// Hints to the compiler about the per-step code (no effect on results).
#pragma once

// NVIB_FLATTEN: every call inside the function is inlined into it (loops.hpp: a loop body used in
// many loops, which the inliner would otherwise call entry by entry).
// NVIB_ALWAYS_INLINE: a small per-step loop inlined where it is called, whatever the inliner's
// budget for the caller (a step whose rare paths take that budget).
// NVIB_NOINLINE: a rarely taken or large path kept out of the per-step code it is called from, so
// that the step around it stays within the inliner's budget.
#if defined(__GNUC__)
#define NVIB_FLATTEN __attribute__((flatten))
#define NVIB_NOINLINE __attribute__((noinline))
#define NVIB_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define NVIB_ALWAYS_INLINE inline
#define NVIB_FLATTEN
#define NVIB_NOINLINE
#endif
