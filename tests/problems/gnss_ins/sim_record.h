// Simulated GNSS/INS records for the estimator tests: a scenario simulated with a seed
// into a temporary folder and read back as a user would (core/io readers), with its truth,
// initial state and errors.yaml; plus small helpers on them.
#pragma once

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "core/io/open.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/ins/nav_error.h"

namespace navtwin::gnss_ins::test_records {

struct SimRecord {
  Inputs inputs;
  std::vector<NavState> truth;  ///< at every IMU epoch (and t = 0)
  NavState init;                ///< init.nav: truth + the scenario's init errors
  YAML::Node errors;            ///< errors.yaml
};

template <typename Sample, typename Reader>
inline std::vector<Sample> ReadAll(const std::unique_ptr<Reader>& reader) {
  std::vector<Sample> out;
  Sample s;
  while (reader->Next(&s)) out.push_back(s);
  return out;
}

/// Simulates `scenario` with `seed` into a temporary folder and reads the files as a user
/// would (the simulated IMU has no mounting rotation or time offset, so its samples are
/// body-axes inputs on the GNSS time scale).
inline SimRecord SimulateRecord(const sim::Scenario& scenario, std::uint64_t seed, bool perfect = false) {
  std::string dir = ::testing::TempDir() + "navtwin_filter_XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  sim::SimulationOptions options;
  options.seed = seed;
  options.perfect = perfect;
  sim::Simulate(scenario, options, dir);
  SimRecord r;
  r.inputs.paths.imu = dir + "/imu.txt";
  r.inputs.imu = ins::ImuRecord(ReadAll<ImuSample>(OpenImu(r.inputs.paths.imu)));
  if (scenario.gnss) {
    r.inputs.paths.gnss = dir + "/gnss.txt";
    r.inputs.gnss = ReadAll<GnssSample>(OpenGnss(r.inputs.paths.gnss));
  }
  if (scenario.mag) {
    r.inputs.paths.mag = dir + "/mag.csv";
    r.inputs.mag = ReadAll<MagSample>(OpenMag(r.inputs.paths.mag));
  }
  if (scenario.baro) {
    r.inputs.paths.baro = dir + "/baro.csv";
    r.inputs.baro = ReadAll<BaroSample>(OpenBaro(r.inputs.paths.baro));
  }
  r.truth = ReadAll<NavState>(OpenNav(dir + "/truth.nav"));
  r.init = ReadAll<NavState>(OpenNav(dir + "/init.nav")).front();
  r.errors = YAML::LoadFile(dir + "/errors.yaml");
  std::filesystem::remove_all(dir);
  return r;
}

inline Eigen::Vector3d Vec3(const YAML::Node& n) {
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

/// The truth at t_s (interpolated between the IMU-rate truth records).
inline NavState TruthAt(const std::vector<NavState>& truth, double t_s) {
  auto it = std::lower_bound(truth.begin(), truth.end(), t_s,
                             [](const NavState& s, double t) { return s.t_s < t; });
  if (it == truth.end()) return truth.back();
  if (std::abs(it->t_s - t_s) < 1e-9 || it == truth.begin()) return *it;
  return InterpolateNav(*(it - 1), *it, t_s);
}

}  // namespace navtwin::gnss_ins::test_records
