// State checkpoints (`run --save-state FILE --frame-of-state F`, `run --load-state FILE`): the
// particles' positions and velocities after a frame, so that an ablation starts every variant
// from one identical state. The file format is in results/README.md ("State checkpoints").
#pragma once

#include "../params.hpp"

#include <Eigen/Dense>

#include <string>

namespace xb {

struct SimState {
  int frame = 0;  // the frame the state starts (the saved frame + 1)
  Eigen::Matrix3Xd x, v;
};

// Writes through a temporary file and a rename (atomic_file.hpp). Records the scene and its parameters as attributes.
void write_state(const std::string& path, const SimState& s, const Params& p);
// Reads a state file; throws xb::Error naming the file for anything that is not one.
SimState read_state(const std::string& path);

}  // namespace xb
