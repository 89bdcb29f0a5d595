// The process's memory as the kernel counts it: the resident set now and at its peak, and the
// limit on its data segment (RLIMIT_DATA: every private writable mapping, the heap and anonymous
// mmaps), which `run --memory-limit` sets so that an allocation past it fails inside the process
// (std::bad_alloc, CHOLMOD's out-of-memory status) instead of the system killing it.
#pragma once

#include <string>

namespace xb {

// Bytes resident now (/proc/self/statm); -1 where it cannot be read.
long long resident_bytes();
// Bytes of the data segment now, as RLIMIT_DATA counts it (/proc/self/statm's data + stack); -1
// where it cannot be read.
long long data_bytes();
// The largest resident set of the process so far (getrusage's ru_maxrss).
long long peak_resident_bytes();
// RLIMIT_DATA's soft limit in bytes; -1 for none.
long long data_limit_bytes();
// Sets RLIMIT_DATA's soft limit (not above the hard one); throws xb::Error where the system refuses.
void set_data_limit(long long bytes);
// Bytes as "8.52 GB" (10^9).
std::string gigabytes(double bytes);

}  // namespace xb
