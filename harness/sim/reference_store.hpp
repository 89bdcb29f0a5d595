// Stored references (`run --reference-file PATH`): the reference of a substep (reference.hpp) is
// computed once and read by every run of the same problem. A substep's reference is read from PATH
// where PATH holds one computed from the same predicted state x̃ (the same bits) of the same
// problem; else it is computed, and added to PATH where PATH holds none for that (frame, substep).
// The problem is what defines the substep's minimisation: every scene key but `frames` (the mesh,
// the material, dt, substeps, init, ...), reference.method and reference.linear, h, and hashes of
// the masses and of α̃; its text and hash head the file (harness/io/reference_file.hpp). A file of
// another problem is an error naming the keys that differ, never a silent reuse.
#pragma once

#include "reference.hpp"

#include "../io/reference_file.hpp"

#include <optional>
#include <string>

namespace xb {

// 16 hex digits of FNV-1a (64 bit) over the bytes.
std::string hash_hex(const void* data, std::size_t n);
// The text that defines the problem of a substep's reference ("key = value" lines).
std::string reference_problem(const Params& p, const Problem& prob, const Eigen::VectorXd& alpha_tilde);

class ReferenceStore {
 public:
  // Throws xb::Error where PATH holds references of another problem (naming what differs), or is
  // not a reference file.
  ReferenceStore(std::string path, const Params& p, const Problem& prob, const Eigen::VectorXd& alpha_tilde);
  // The stored reference of (frame, substep) where it was computed from x_pred; else nullopt.
  // Throws xb::Error for a stored reference that lacks a field (an older file).
  std::optional<ReferenceSolution> find(int frame, int substep, const Eigen::Matrix3Xd& x_pred) const;
  // Stores `r` (computed from x_pred in `seconds`), unless PATH holds a reference of (frame,
  // substep) already (one from another x̃: the run's own trajectory); true where it did.
  bool store(int frame, int substep, const Eigen::Matrix3Xd& x_pred, const ReferenceSolution& r, double seconds) const;
  // The description of the stored references' method (the file's, where it has one).
  const std::string& method() const { return header_.method; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  ReferenceFileHeader header_;
};

}  // namespace xb
