// How much memory the machine can give, for the limit on a run's saved history.
#pragma once

#include <cstdio>
#include <cstring>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace nvib {

// Bytes of memory available now: MemAvailable of /proc/meminfo on Linux, else the free physical
// pages; 0 if unknown (then no limit applies).
inline double available_memory_bytes() {
#if defined(__linux__)
  if (std::FILE* f = std::fopen("/proc/meminfo", "r")) {
    char line[256];
    double kb = -1.0;
    while (std::fgets(line, sizeof line, f))
      if (std::strncmp(line, "MemAvailable:", 13) == 0) {
        kb = std::strtod(line + 13, nullptr);
        break;
      }
    std::fclose(f);
    if (kb > 0.0) return kb * 1024.0;
  }
#endif
#if defined(_SC_AVPHYS_PAGES) && defined(_SC_PAGESIZE)
  const long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  if (pages > 0 && size > 0) return static_cast<double>(pages) * static_cast<double>(size);
#endif
  return 0.0;
}

}  // namespace nvib
