// For the tests that check that a step allocates nothing: include it first, before nvib.hpp. Eigen's own
// allocations are trapped with EIGEN_RUNTIME_NO_MALLOC (its assertion made to throw); every other heap
// allocation (std::vector, std::string) is counted by a replaced global operator new while g_counting is set.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>
#include <stdexcept>

#undef NDEBUG  // Eigen's malloc check is an eigen_assert
#define EIGEN_RUNTIME_NO_MALLOC
#define eigen_assert(x) \
  if (!(x)) throw std::runtime_error("eigen_assert failed: " #x)

static std::atomic<long> g_news{0};
static std::atomic<bool> g_counting{false};

void* operator new(std::size_t n) {
  if (g_counting) ++g_news;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
