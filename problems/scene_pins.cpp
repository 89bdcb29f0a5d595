#include "scene_pins.hpp"

#include "../core/error.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace xb {

std::vector<double> list_numbers(const std::string& key, const std::string& text) {
  std::string spaced = text;
  for (char& c : spaced)
    if (c == ',') c = ' ';
  std::istringstream in(spaced);
  std::vector<double> out;
  for (std::string item; in >> item;) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end != item.c_str() + item.size() || !std::isfinite(v))
      throw Error("parameter '" + key + "' = '" + text + "': '" + item + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

std::string scene_text_error(const std::string& key, const std::string& value) {
  try {
    if (key == "pins.indices") {
      for (double v : list_numbers(key, value))
        if (v < 0 || v != std::floor(v) || v > 2147483647.0) {
          std::ostringstream os;
          os << "'" << v << "' is not a particle index (an integer >= 0)";
          return os.str();
        }
    } else if (key == "pins.box") {
      const std::vector<double> b = list_numbers(key, value);
      if (b.size() % 6 != 0)
        return std::to_string(b.size()) + " numbers: a box is 6 (xmin, ymin, zmin, xmax, ymax, zmax), several boxes 6 each";
      for (size_t i = 0; i < b.size(); i += 6)
        for (int d = 0; d < 3; ++d)
          if (b[i + d] > b[i + 3 + d]) return "box " + std::to_string(i / 6 + 1) + " has a minimum above its maximum";
    } else if (key == "ground" && value != "builder" && value != "none") {
      const std::vector<double> h = list_numbers(key, value);
      if (h.size() != 1) return "builder, none or one height in m";
    }
  } catch (const Error& e) {
    const std::string what = e.what();
    return what.substr(what.find(": ") + 2);
  }
  return "";
}

void apply_pins_and_ground(const SceneSettings& p, Problem& prob) {
  Particles& P = prob.particles;
  const int n = P.size();
  if (p.builder_pins == "none")
    for (int i = 0; i < n; ++i)
      if (P.w[i] == 0) P.w[i] = 1.0 / p.particle_mass;
  for (double v : list_numbers("pins.indices", p.pin_indices)) {
    if (v >= n)
      throw Error("parameter 'pins.indices' = '" + p.pin_indices + "': particle " + std::to_string(static_cast<long>(v)) +
                  " is out of range (scene '" + p.scene + "' has " + std::to_string(n) + " particles, 0 to " + std::to_string(n - 1) + ")");
    P.w[static_cast<int>(v)] = 0;
  }
  const std::vector<double> b = list_numbers("pins.box", p.pin_box);
  for (size_t k = 0; k + 5 < b.size(); k += 6) {
    int pinned = 0;
    for (int i = 0; i < n; ++i) {
      bool inside = true;
      for (int d = 0; d < 3; ++d) inside = inside && P.x(d, i) >= b[k + d] && P.x(d, i) <= b[k + 3 + d];
      if (inside) P.w[i] = 0, ++pinned;
    }
    if (pinned == 0) {
      std::ostringstream os;
      os << "parameter 'pins.box' = '" << p.pin_box << "': box " << k / 6 + 1 << " holds no particle of scene '" << p.scene
         << "' at its start (x in [" << P.x.row(0).minCoeff() << ", " << P.x.row(0).maxCoeff() << "], y in ["
         << P.x.row(1).minCoeff() << ", " << P.x.row(1).maxCoeff() << "], z in [" << P.x.row(2).minCoeff() << ", "
         << P.x.row(2).maxCoeff() << "])";
      throw Error(os.str());
    }
  }
  if (p.ground == "none") prob.planes.clear();
  else if (p.ground != "builder") prob.planes = {PlaneCollider{list_numbers("ground", p.ground).at(0)}};
}

}  // namespace xb
