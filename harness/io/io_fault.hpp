// Deterministic write faults, the test hook of the atomic-file layer (docs/failures.md):
//   XB_FAULT_WRITE=N:ERRNO   the N-th write call of this process fails with ERRNO
//   XB_FAULT_RENAME=N:ERRNO  the N-th rename of a finished temporary file over its PATH fails with ERRNO
// A write call is one chunk of at most write_chunk bytes written to a temporary file, or the fsync
// that ends each file; both are counted from 1 over the whole process. ERRNO is a name: ENOSPC,
// EFBIG, EROFS, EDQUOT, EIO or EACCES. Honoured by every build, so that the binary and the Python
// module under test are the ones users run; the cost is one counter per 16 KiB written, far from
// any solver.
#pragma once

#include <string>

namespace xb::io_fault {

// 0, or the errno the write (rename) now being made must fail with. The first call reads the
// environment and throws xb::Error naming the variable if its value is not N:ERRNO.
int next_write();
int next_rename();
// The write calls this process has made so far (what an append costs, in tests).
long write_calls();
// In-process tests: replaces the environment's settings ("" = no fault) and restarts the counts.
void set(const std::string& write, const std::string& rename);

}  // namespace xb::io_fault
