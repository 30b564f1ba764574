// Interrupting long work. Operations that can take seconds (the solve loop,
// model assembly, a factorisation's set-up, PIM's exponential) call
// poll_interrupt() between pieces of work; an embedding installs a hook for
// the current thread (the Python binding checks for Ctrl-C there) that throws
// to stop the work. Without a hook, polling costs a thread-local load.
//
// ClockPoll spaces the polls by elapsed time, not by a count of calls: it
// reads the clock every `stride` calls, the stride adapting so that the clock
// is read about once a millisecond, and calls the hook about every `period`.
// A step of a second is then followed by a poll; a step of 50 ns costs a
// countdown.
#pragma once

#include <chrono>
#include <cstdint>

#include "compiler.hpp"

namespace nvib {

struct InterruptHook {
  void (*poll)(void* data) = nullptr;
  void* data = nullptr;
};

inline InterruptHook& interrupt_hook() {
  thread_local InterruptHook hook;
  return hook;
}

inline void poll_interrupt() {
  const InterruptHook& h = interrupt_hook();
  if (h.poll != nullptr) h.poll(h.data);
}

// Installs a hook for the current thread for its lifetime (the previous one is restored).
class ScopedInterruptHook {
 public:
  ScopedInterruptHook(void (*poll)(void*), void* data) : previous_(interrupt_hook()) {
    interrupt_hook() = InterruptHook{poll, data};
  }
  ~ScopedInterruptHook() { interrupt_hook() = previous_; }
  ScopedInterruptHook(const ScopedInterruptHook&) = delete;
  ScopedInterruptHook& operator=(const ScopedInterruptHook&) = delete;

 private:
  InterruptHook previous_;
};

class ClockPoll {
 public:
  using clock = std::chrono::steady_clock;
  explicit ClockPoll(double period_seconds = 0.05)
      : period_(std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(period_seconds))),
        last_read_(clock::now()),
        last_fire_(last_read_) {}

  // True about every period of work (then the caller observes); cheap otherwise.
  bool tick() {
    if (--countdown_ > 0) return false;  // the per-step path: inlined into the caller's loop
    return read_clock();
  }

 private:
  NVIB_NOINLINE bool read_clock() {
    const auto now = clock::now();
    const auto since = now - last_read_;
    if (since < std::chrono::microseconds(500) && stride_ < (std::int64_t(1) << 24))
      stride_ *= 2;
    else if (since > std::chrono::milliseconds(2) && stride_ > 1)
      stride_ /= 2;
    countdown_ = stride_;
    last_read_ = now;
    if (now - last_fire_ < period_) return false;
    last_fire_ = now;
    return true;
  }

  clock::duration period_;
  clock::time_point last_read_, last_fire_;
  std::int64_t stride_ = 1, countdown_ = 1;
};

}  // namespace nvib
