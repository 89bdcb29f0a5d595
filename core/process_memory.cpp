#include "process_memory.hpp"

#include "error.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace xb {

long long resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  long long size = 0, resident = 0;
  const int got = std::fscanf(f, "%lld %lld", &size, &resident);
  std::fclose(f);
  return got == 2 ? resident * sysconf(_SC_PAGESIZE) : -1;
}

long long data_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  long long v[6] = {};
  const int got = std::fscanf(f, "%lld %lld %lld %lld %lld %lld", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]);
  std::fclose(f);
  return got == 6 ? v[5] * sysconf(_SC_PAGESIZE) : -1;
}

long long peak_resident_bytes() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return -1;
  return static_cast<long long>(u.ru_maxrss) * 1024;  // Linux: KiB
}

long long data_limit_bytes() {
  rlimit r{};
  if (getrlimit(RLIMIT_DATA, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return -1;
  return static_cast<long long>(r.rlim_cur);
}

void set_data_limit(long long bytes) {
  rlimit r{};
  if (getrlimit(RLIMIT_DATA, &r) != 0) throw Error(std::string("getrlimit(RLIMIT_DATA): ") + std::strerror(errno));
  if (r.rlim_max != RLIM_INFINITY && static_cast<rlim_t>(bytes) > r.rlim_max)
    throw Error("memory limit " + gigabytes(static_cast<double>(bytes)) + " is above the process's hard limit " +
                gigabytes(static_cast<double>(r.rlim_max)));
  r.rlim_cur = static_cast<rlim_t>(bytes);
  if (setrlimit(RLIMIT_DATA, &r) != 0) throw Error(std::string("setrlimit(RLIMIT_DATA): ") + std::strerror(errno));
}

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  return text;
}

}  // namespace xb
