// A file of stored references (`run --reference-file PATH`, harness/sim/reference_store.hpp): the
// reference solutions of one problem, each computed once and read by every run of that problem.
// The format is in results/README.md ("Reference files"). Plain types only: the simulation turns
// them into its ReferenceSolution.
#pragma once

#include "record.hpp"

#include <Eigen/Dense>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace xb {

// What the file's references are references of: the hash of the problem's definition and the
// text it was computed from (a mismatch names the keys that differ), and how they were computed.
struct ReferenceFileHeader {
  std::string problem_hash;  // 16 hex digits
  std::string problem;       // "key = value" lines
  std::string method;        // the reference's description (reference_method of a run)
  long long particles = 0;
};

// One substep's reference: where (frame, substep), from which predicted state x̃ (its hash: a
// reference is the solution of the substep that starts there), the positions and every other
// field of the reference by name.
struct StoredReference {
  long long frame = 0, substep = 0;
  std::string state_hash;
  Eigen::Matrix3Xd x;
  std::map<std::string, AttrValue> fields;
};

// The header of a reference file; nullopt where no file is at `path`. Throws xb::Error naming the
// file for one that is not a reference file.
std::optional<ReferenceFileHeader> read_reference_header(const std::string& path);
// The reference of (frame, substep); nullopt where the file has none.
std::optional<StoredReference> read_reference(const std::string& path, long long frame, long long substep);
// Adds `ref` to the file (made with `header` where missing) under an exclusive lock on PATH.lock,
// whole or not at all (atomic_file.hpp); a reference already stored for (frame, substep) is kept
// and false returned. Throws xb::Error where the file's header is not `header`'s problem.
bool add_reference(const std::string& path, const ReferenceFileHeader& header, const StoredReference& ref);

}  // namespace xb
