// Numbers in messages and argument checks. No iostreams: a module that links
// libstdc++ statically can crash inside std::ostream << double, and a check
// that passes should cost nothing, so messages are built only on failure.
#pragma once

#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

namespace nvib {

// A bad argument: `argument` names it ("eta", "effects[3].measure"); the
// message is "<argument>: <what is wrong>".
class ArgumentError : public std::invalid_argument {
 public:
  ArgumentError(std::string argument, const std::string& what)
      : std::invalid_argument(argument + ": " + what), argument_(std::move(argument)) {}
  const std::string& argument() const { return argument_; }

 private:
  std::string argument_;
};

namespace detail {

// Shortest form with 6 significant digits, like printf's %g, independent of the locale.
inline std::string fmt(double x) {
  char buf[32];
#if defined(__cpp_lib_to_chars) && __cpp_lib_to_chars >= 201611L
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 6);
  return std::string(buf, r.ptr);
#else
  const int n = std::snprintf(buf, sizeof buf, "%.6g", x);
  return std::string(buf, static_cast<size_t>(n));
#endif
}

// The shortest decimal that reads back as x (for reprs that round-trip).
inline std::string repr(double x) {
  char buf[32];
#if defined(__cpp_lib_to_chars) && __cpp_lib_to_chars >= 201611L
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
#else
  const int n = std::snprintf(buf, sizeof buf, "%.17g", x);
  return std::string(buf, static_cast<size_t>(n));
#endif
}

[[noreturn]] inline void throw_argument(std::string argument, const std::string& what) {
  throw ArgumentError(std::move(argument), what);
}

}  // namespace detail
}  // namespace nvib

// NVIB_CHECK(condition, argument, what): throws ArgumentError(argument, what)
// when the condition fails; `what` is evaluated only then.
#define NVIB_CHECK(condition, argument, what)                        \
  do {                                                               \
    if (!(condition)) ::nvib::detail::throw_argument((argument), (what)); \
  } while (0)
