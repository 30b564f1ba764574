// Numbers in messages. No iostreams: a module that links libstdc++ statically
// can crash inside std::ostream << double.
#pragma once

#include <charconv>
#include <cstdio>
#include <string>

namespace nvib {

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

}  // namespace detail
}  // namespace nvib
