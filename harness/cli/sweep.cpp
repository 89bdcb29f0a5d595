#include "sweep.hpp"

#include "args.hpp"
#include "report.hpp"
#include "profile.hpp"
#include "run_setup.hpp"
#include "../io/run_record.hpp"
#include "../key_check.hpp"

#include "../../core/error.hpp"
#include "../../core/toml_flat.hpp"
#include "../../problems/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <set>

namespace fs = std::filesystem;

namespace xb {

namespace {

const std::vector<std::string> top_keys = {"scene", "solvers", "frames", "repeats", "time_budget", "reference",
                                           "description", "profile", "set", "grid"};

std::string join(const std::vector<std::string>& v, const std::string& sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

double parse_number(const std::string& where, const std::string& key, const std::string& text) {
  double v = 0;
  if (const std::string why = parse_finite(text, v); !why.empty()) throw Error(where + ": '" + key + "' = '" + text + "': " + why);
  return v;
}

// A scene given as a path is looked up beside the spec first.
std::string resolve_spec_scene(const std::string& spec_path, const std::string& scene) {
  const bool is_path = scene.find('/') != std::string::npos || scene.ends_with(".toml");
  if (is_path && !fs::path(scene).is_absolute() && !fs::exists(scene)) {
    const fs::path beside = fs::path(spec_path).parent_path() / scene;
    if (fs::exists(beside)) return resolve_scene(beside.string());
  }
  return resolve_scene(scene);
}

std::string fnv1a_hex(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

Params base_params(const SweepSpec& spec) {
  Params p;
  load_scene_file(spec.scene, p);
  if (!spec.profile.empty()) apply_profile(spec.profile, p);
  for (const auto& kv : spec.sets) {
    const std::string key = kv.substr(0, kv.find('='));
    set_param(p, key, kv.substr(kv.find('=') + 1), spec.path + ": [set] '" + key + "'");
  }
  return p;
}

}  // namespace

std::string canonical_value(const Params& p, const std::string& key) {
  const ParamField* f = find_param(key);
  if (!f) throw Error("unknown parameter '" + key + "'");
  const ParamValue v = param_value(p, *f);
  if (auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&v)) {
    char b[40];
    std::snprintf(b, sizeof b, "%.15g", *d);
    return b;
  }
  return std::get<std::string>(v);
}

namespace {
// The spec's entries at one size: a [sizes.NAME] table's keys (frames, time_budget, set.*,
// grid.*, ...) replace or add to the top-level ones; the other sizes are dropped. "default"
// needs no table. Throws for an unknown size, naming the ones the spec has.
std::vector<TomlEntry> entries_at_size(const std::string& path, const std::string& size) {
  std::vector<TomlEntry> base, sized;
  std::vector<std::string> sizes;
  for (auto e : read_toml_flat(path)) {
    if (e.key.rfind("sizes.", 0) != 0) {
      base.push_back(std::move(e));
      continue;
    }
    const std::string rest = e.key.substr(6);
    const size_t dot = rest.find('.');
    const std::string name = rest.substr(0, dot);
    if (dot == std::string::npos) throw Error(path + ":" + std::to_string(e.line) + ": '" + e.key + "' must be a table ([sizes." + name + "])");
    if (std::find(sizes.begin(), sizes.end(), name) == sizes.end()) sizes.push_back(name);
    if (name != size) continue;
    e.key = rest.substr(dot + 1);
    sized.push_back(std::move(e));
  }
  if (size != "default" && std::find(sizes.begin(), sizes.end(), size) == sizes.end())
    throw Error(path + ": no size '" + size + "' (sizes: default" + (sizes.empty() ? "" : ", " + join(sizes)) + ")");
  for (auto& e : sized) {
    auto same = std::find_if(base.begin(), base.end(), [&](const TomlEntry& b) { return b.key == e.key; });
    if (same != base.end())
      *same = std::move(e);
    else
      base.push_back(std::move(e));
  }
  return base;
}
}  // namespace

namespace {
// The fixed overrides (frames, [set]) and the grid axes, each value checked on its own so an
// error names its line.
void add_sets_and_grid(SweepSpec& spec, const std::string& frames, int frames_line,
                       const std::vector<const TomlEntry*>& sets, const std::vector<const TomlEntry*>& grids) {
  auto where = [&](const TomlEntry& e) { return spec.path + ":" + std::to_string(e.line); };
  Params probe;
  load_scene_file(spec.scene, probe);
  if (!frames.empty()) {
    set_param(probe, "frames", frames, spec.path + ":" + std::to_string(frames_line));
    spec.sets.push_back("frames=" + frames);
  }
  for (const TomlEntry* e : sets) {
    const std::string key = e->key.substr(4);
    const ParamField* f = find_param(key);
    if (e->is_array && !(f && f->list))
      throw Error(where(*e) + ": [set] '" + key + "' must be a single value (lists belong in [grid])");
    TomlEntry one = *e;
    one.key = key;
    const std::string value = entry_value(one, where(*e));
    set_param(probe, key, value, where(*e));
    spec.sets.push_back(key + "=" + value);
  }
  std::set<std::string> fixed_keys;
  for (const auto& kv : spec.sets) fixed_keys.insert(kv.substr(0, kv.find('=')));
  for (const TomlEntry* e : grids) {
    const std::string key = e->key.substr(5);
    if (!e->is_array) throw Error(where(*e) + ": [grid] '" + key + "' must be a list of values");
    if (e->items.empty()) throw Error(where(*e) + ": [grid] '" + key + "' is an empty list");
    if (fixed_keys.count(key)) throw Error(where(*e) + ": '" + key + "' is both fixed ([set] or frames) and swept ([grid])");
    if (key == "scene") throw Error(where(*e) + ": 'scene' cannot be swept (one sweep, one scene builder)");
    std::set<std::string> seen;
    for (const auto& v : e->items) {
      Params q = probe;
      set_param(q, key, v, where(*e));
      if (!seen.insert(canonical_value(q, key)).second)
        throw Error(where(*e) + ": [grid] '" + key + "' lists the value " + v + " twice");
    }
    spec.grid.emplace_back(key, e->items);
  }
}
}  // namespace

SweepSpec parse_sweep_spec(const std::string& path, const std::string& size, const std::string& profile) {
  SweepSpec spec;
  spec.path = path;
  spec.size = size;
  const auto entries = entries_at_size(path, size);
  auto where = [&](const TomlEntry& e) { return path + ":" + std::to_string(e.line); };
  auto scalar = [&](const TomlEntry& e) {
    if (e.is_array) throw Error(where(e) + ": '" + e.key + "' must be a single value, not a list");
    return e.value;
  };
  std::string frames;
  int frames_line = 0;
  std::vector<const TomlEntry*> sets, grids;
  bool have_solvers = false;
  for (const auto& e : entries) {
    const std::string head = e.key.substr(0, e.key.find('.'));
    if (std::find(top_keys.begin(), top_keys.end(), head) == top_keys.end() ||
        (head != "set" && head != "grid" && e.key != head))
      throw Error(where(e) + ": unknown key '" + e.key + "' (valid: " + join(top_keys) + ")");
    if (head == "set" || head == "grid") {
      if (e.key == head) throw Error(where(e) + ": '" + head + "' must be a table ([" + head + "])");
      (head == "set" ? sets : grids).push_back(&e);
    } else if (e.key == "scene") {
      spec.scene = resolve_spec_scene(path, scalar(e));
    } else if (e.key == "solvers") {
      const std::vector<std::string> names = e.is_array ? e.items : split_list(e.value);
      if (names.empty()) throw Error(where(e) + ": 'solvers' is empty");
      try {
        spec.solvers = parse_methods(join(names, ","), false, true);  // under mpirun: cmd_sweep.cpp decides
      } catch (const Error& err) {
        throw Error(where(e) + ": " + err.what());
      }
      std::set<std::string> seen;
      for (const auto& n : spec.solvers)
        if (!seen.insert(n).second) throw Error(where(e) + ": solver '" + n + "' is listed twice");
      have_solvers = true;
    } else if (e.key == "frames") {
      frames = scalar(e);
      frames_line = e.line;
    } else if (e.key == "repeats") {
      const double r = parse_number(where(e), e.key, scalar(e));
      if (r < 1 || r > 1e6 || r != std::floor(r)) throw Error(where(e) + ": 'repeats' must be an integer >= 1");
      spec.repeats = static_cast<int>(r);
    } else if (e.key == "time_budget") {
      spec.time_budget = parse_number(where(e), e.key, scalar(e));
      if (spec.time_budget < 0) throw Error(where(e) + ": 'time_budget' must be >= 0 (s; 0 = none)");
    } else if (e.key == "reference") {
      const std::string v = scalar(e);
      if (v == "1" || v == "true") spec.reference = true;
      else if (v == "0" || v == "false") spec.reference = false;
      else throw Error(where(e) + ": 'reference' must be true or false");
    } else if (e.key == "description") {
      spec.description = scalar(e);
    } else if (e.key == "profile") {
      spec.profile = scalar(e);
      try {
        resolve_profile(spec.profile);
      } catch (const Error& err) {
        throw Error(where(e) + ": " + err.what());
      }
    }
  }
  if (!profile.empty()) spec.profile = profile;
  if (spec.scene.empty()) throw Error(path + ": missing 'scene' (a built-in scene name or a .toml file)");
  if (!have_solvers) throw Error(path + ": missing 'solvers' (a list of solver names)");
  add_sets_and_grid(spec, frames, frames_line, sets, grids);
  return spec;
}

std::string sweep_base_hash(const SweepSpec& spec) {
  // What the spec fixes, not the whole parameter table: a key added to Params later (with its
  // default) must not make an existing results file look like another sweep. The scene file's
  // text stands for the scene's own settings.
  std::ifstream in(spec.scene, std::ios::binary);
  std::ostringstream text;
  text << "scene_file=" << in.rdbuf() << "\n";
  if (!spec.profile.empty()) {
    std::ifstream prof(resolve_profile(spec.profile), std::ios::binary);
    text << "profile_file=" << prof.rdbuf() << "\n";
  }
  const Params p = base_params(spec);
  std::vector<std::string> fixed;
  for (const auto& kv : spec.sets) {
    const std::string key = kv.substr(0, kv.find('='));
    fixed.push_back(key + "=" + canonical_value(p, key));
  }
  std::sort(fixed.begin(), fixed.end());
  fixed.erase(std::unique(fixed.begin(), fixed.end()), fixed.end());
  for (const auto& f : fixed) text << f << "\n";
  text << "reference=" << (spec.reference ? "1" : "0") << "\n";
  return fnv1a_hex(text.str());
}

std::vector<SweepJob> expand_sweep(const SweepSpec& spec) {
  const Params base = base_params(spec);
  const std::string hash = sweep_base_hash(spec);
  // The run count, multiplied with a cap so that no product overflows (2^64 points must not wrap to 0).
  constexpr size_t max_runs = 1000000;
  size_t points = 1, runs = spec.solvers.size() * static_cast<size_t>(spec.repeats);
  for (const auto& [k, v] : spec.grid) {
    points *= v.size();
    if (points > max_runs || runs * v.size() > max_runs)
      throw Error(spec.path + ": the sweep has over 1e6 runs (reached at grid axis '" + k + "')");
    runs *= v.size();
  }
  if (runs > max_runs) throw Error(spec.path + ": the sweep has over 1e6 runs");
  std::vector<SweepJob> jobs;
  for (size_t pt = 0; pt < points; ++pt) {
    Params p = base;
    std::vector<std::pair<std::string, std::string>> values;
    // Last axis fastest, like nested loops in spec order.
    size_t rest = pt, stride = points;
    for (const auto& [key, vals] : spec.grid) {
      stride /= vals.size();
      const size_t i = rest / stride;
      rest %= stride;
      set_param(p, key, vals[i], spec.path + ": [grid] axis '" + key + "'");
    }
    std::string point_text;
    for (const auto& [key, vals] : spec.grid) {
      values.emplace_back(key, canonical_value(p, key));
      point_text += (point_text.empty() ? "" : " ") + key + "=" + values.back().second;
    }
    if (point_text.empty()) point_text = "-";
    try {
      validate(p);
      check_scene_keys(p);
    } catch (const Error& e) {
      throw Error(spec.path + ": grid point " + point_text + ": " + e.what());
    }
    for (const auto& solver : spec.solvers)
      for (int r = 0; r < spec.repeats; ++r) {
        SweepJob j;
        j.index = static_cast<int>(jobs.size());
        j.params = p;
        j.solver = solver;
        j.repeat = r;
        j.point = static_cast<int>(pt);
        j.values = values;
        j.point_text = point_text;
        j.key = hash + "|" + point_text + "|solver=" + solver + "|repeat=" + std::to_string(r);
        jobs.push_back(std::move(j));
      }
  }
  // Every key the spec sets, and every grid axis, must change one of its runs.
  std::vector<CommandRun> checked;
  for (const auto& j : jobs)
    if (j.repeat == 0) checked.push_back({j.params, j.solver, spec.reference});
  check_keys(checked);
  return jobs;
}

}  // namespace xb
