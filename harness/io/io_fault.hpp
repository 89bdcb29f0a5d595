// Deterministic faults, the test hook of the atomic-file layer and of the results store
// (docs/failures.md):
//   XB_FAULT_WRITE=N:ERRNO    the N-th write call of this process fails with ERRNO
//   XB_FAULT_RENAME=N:ERRNO   the N-th rename (or link) of a finished temporary file into place fails with ERRNO
//   XB_FAULT_LOCK=N:ERRNO     the N-th attempt to take a results file's lock fails with ERRNO (ENOLCK:
//                             a file system without locks)
//   XB_FAULT_SIGNAL=N:SIGNAL  the process sends itself SIGKILL or SIGSTOP just before its N-th durable
//                             step: an fsync of a file or of a folder, a rename or a link into place
// A write call is one chunk of at most write_chunk bytes written to a temporary file, or the fsync
// that ends each file; every count starts at 1 over the whole process. ERRNO is a name: ENOSPC,
// EFBIG, EROFS, EDQUOT, EIO, EACCES or ENOLCK. Honoured by every build, so that the binary and the
// Python module under test are the ones users run; the cost is one counter per 16 KiB written or
// per step, far from any solver.
#pragma once

#include <string>

namespace xb::io_fault {

// 0, or the errno the write (rename, lock) now being made must fail with. The first call reads the
// environment and throws xb::Error naming the variable if its value is not N:ERRNO.
int next_write();
int next_rename();
int next_lock();
// Counts a durable step and, at XB_FAULT_SIGNAL's N, stops or kills this process first.
void durable_step();
// The write calls (durable steps) this process has made so far (what an append costs, in tests).
long write_calls();
long steps();
// In-process tests: replaces the environment's settings ("" = no fault) and restarts the counts.
void set(const std::string& write, const std::string& rename, const std::string& lock = "");

}  // namespace xb::io_fault
