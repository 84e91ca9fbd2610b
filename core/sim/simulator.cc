#include "core/sim/simulator.h"

#include <stdlib.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <system_error>

#include "core/io/atomic_file.h"
#include "core/io/csv_mag_baro.h"
#include "core/io/kfgins.h"
#include "core/rotation.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/truth.h"

namespace navtwin::sim {
namespace {

/// The initial state given to an estimator: truth at t = 0 with the configured errors.
NavState InitialState(const NavState& truth, const InitErrorConfig& e) {
  NavState s = truth;
  const wgs84::Geodetic p =
      wgs84::NedToGeodetic(e.position_ned_m, {truth.lat_rad, truth.lon_rad, truth.h_m});
  s.lat_rad = p.lat_rad;
  s.lon_rad = p.lon_rad;
  s.h_m = p.h_m;
  s.v_n_mps += e.velocity_ned_mps;
  // R_true = Exp(phi) R_init  =>  R_init = Exp(-phi) R_true.
  s.q_n_b = ApplyAttitudeError<double>(-e.attitude_phi_n_rad, truth.q_n_b);
  return s;
}

/// Feeds one truth sample to an aiding simulator (if the scenario has it) and writes the
/// sample it emits, if any.
template <typename Simulator, typename Writer>
void PushAndWrite(Simulator* simulator, Writer* writer, const TruthSample& truth, std::size_t* count) {
  if (simulator == nullptr) return;
  if (const auto sample = simulator->Push(truth)) {
    writer->Write(*sample);
    ++*count;
  }
}

/// The pendulum's pivot encoder: the true angle plus white noise, read to a multiple of the
/// quantum (an absolute encoder: the rounding error does not carry over); angle.csv.
class AngleEncoder {
 public:
  AngleEncoder(const PendulumRig& rig, const Rng& rng, bool perfect, const std::string& path)
      : rig_(rig), rng_(rng), file_(path) {
    if (!perfect) {
      noise_rad_ = rig.config().angle_noise_rad;
      quantum_rad_ = rig.config().angle_quantum_rad;
    }
    file_.stream() << "t_s,theta_rad\n";
  }
  /// The reading at the truth time truth_t_s, tagged t_s (the IMU sample's time tag).
  void Write(double t_s, double truth_t_s) {
    double theta = rig_.Angle_rad(truth_t_s) + rng_.Normal(noise_rad_);
    if (quantum_rad_ > 0.0) theta = quantum_rad_ * std::round(theta / quantum_rad_);
    file_.stream() << t_s << ',' << theta << '\n';
  }
  void Commit() { file_.Commit(); }

 private:
  const PendulumRig& rig_;
  Rng rng_;
  AtomicFile file_;
  double noise_rad_ = 0.0, quantum_rad_ = 0.0;
};

/// The IMU's temperature sensor: the profile's temperature at the sample's truth time,
/// tagged with the IMU sample's time tag; temperature.csv.
class TemperatureSensor {
 public:
  TemperatureSensor(const TemperatureProfile& profile, const std::string& path) : profile_(profile), file_(path) {
    file_.stream() << "t_s,temperature_degC\n";
  }
  void Write(double t_s, double truth_t_s) { file_.stream() << t_s << ',' << profile_.At(truth_t_s) << '\n'; }
  void Commit() { file_.Commit(); }

 private:
  const TemperatureProfile& profile_;
  AtomicFile file_;
};

}  // namespace

SimulationReport Simulate(const Scenario& scenario, const SimulationOptions& options,
                          const std::string& out_dir) {
  const auto wall_start = std::chrono::steady_clock::now();
  const Rng rng(options.seed);
  const bool perfect = options.perfect;
  SimulationReport report;
  const auto path = [&](const char* name) {
    report.files.push_back(out_dir + "/" + name);
    return report.files.back();
  };

  ImuSimulator imu(scenario.imu, rng, perfect);
  TruthGenerator truth(*scenario.trajectory, scenario.start, imu.internal_rate_hz());
  KfginsImuWriter imu_out(path("imu.txt"));
  KfginsNavWriter truth_out(path("truth.nav"));
  KfginsNavWriter init_out(path("init.nav"));

  std::unique_ptr<GnssSimulator> gnss;
  std::unique_ptr<KfginsGnssWriter> gnss_out;
  if (scenario.gnss) {
    gnss = std::make_unique<GnssSimulator>(*scenario.gnss, rng.Stream("gnss"), perfect);
    gnss_out = std::make_unique<KfginsGnssWriter>(path("gnss.txt"));
  }
  std::unique_ptr<MagSimulator> mag;
  std::unique_ptr<CsvMagWriter> mag_out;
  if (scenario.mag) {
    mag = std::make_unique<MagSimulator>(*scenario.mag, scenario.start.lat_rad, rng.Stream("mag"), perfect);
    mag_out = std::make_unique<CsvMagWriter>(path("mag.csv"));
  }
  std::unique_ptr<BaroSimulator> baro;
  std::unique_ptr<CsvBaroWriter> baro_out;
  if (scenario.baro) {
    baro = std::make_unique<BaroSimulator>(*scenario.baro, rng.Stream("baro"), perfect);
    baro_out = std::make_unique<CsvBaroWriter>(path("baro.csv"));
  }
  std::unique_ptr<OdometerSimulator> odometer;
  std::unique_ptr<CsvOdometerWriter> odometer_out;
  if (scenario.odometer) {
    odometer = std::make_unique<OdometerSimulator>(*scenario.odometer, rng.Stream("odometer"), perfect);
    odometer_out = std::make_unique<CsvOdometerWriter>(path("odometer.csv"));
  }
  std::unique_ptr<MasterSimulator> master;
  std::unique_ptr<KfginsNavWriter> master_out;
  if (scenario.master) {
    master = std::make_unique<MasterSimulator>(*scenario.master, rng.Stream("master"), perfect);
    master_out = std::make_unique<KfginsNavWriter>(path("master.nav"));
  }

  std::unique_ptr<AngleEncoder> angle_out;
  if (const auto* rig = dynamic_cast<const PendulumRig*>(scenario.trajectory.get())) {
    angle_out = std::make_unique<AngleEncoder>(*rig, rng.Stream("angle"), perfect, path("angle.csv"));
  }

  std::unique_ptr<TemperatureSensor> temperature_out;
  const TemperatureProfile& profile = scenario.imu.errors.temperature;
  if (profile.initial_degC != profile.final_degC) {
    temperature_out = std::make_unique<TemperatureSensor>(profile, path("temperature.csv"));
  }

  const long n = std::lround(scenario.duration_s * imu.internal_rate_hz());
  const long progress_step = std::max(1L, n / 20);
  for (long k = 0; k <= n; ++k) {
    const TruthSample& t = k == 0 ? truth.current() : truth.Next();
    if (k == 0) {
      truth_out.Write(t.state);
      init_out.Write(InitialState(t.state, scenario.init_errors));
    }
    if (const auto s = imu.Push(t)) {
      imu_out.Write(*s);
      truth_out.Write(t.state);
      if (angle_out) angle_out->Write(s->t_s, t.t_s);
      if (temperature_out) temperature_out->Write(s->t_s, t.t_s);
      ++report.imu_samples;
    }
    PushAndWrite(gnss.get(), gnss_out.get(), t, &report.gnss_samples);
    PushAndWrite(mag.get(), mag_out.get(), t, &report.mag_samples);
    PushAndWrite(baro.get(), baro_out.get(), t, &report.baro_samples);
    PushAndWrite(odometer.get(), odometer_out.get(), t, &report.odometer_samples);
    PushAndWrite(master.get(), master_out.get(), t, &report.master_samples);
    if (options.progress && k % progress_step == 0) options.progress(static_cast<double>(k) / n);
  }

  // errors.yaml: the seed and every drawn value.
  AtomicFile errors(path("errors.yaml"));
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "scenario" << YAML::Value << scenario.name;
  y << YAML::Key << "seed" << YAML::Value << options.seed;
  y << YAML::Key << "perfect" << YAML::Value << perfect;
  y << YAML::Key << "duration_s" << YAML::Value << scenario.duration_s;
  y << YAML::Key << "imu" << YAML::Value;
  imu.EmitDrawn(y);
  if (gnss) {
    y << YAML::Key << "gnss" << YAML::Value;
    gnss->EmitDrawn(y);
  }
  if (mag) {
    y << YAML::Key << "mag" << YAML::Value;
    mag->EmitDrawn(y);
  }
  if (baro) {
    y << YAML::Key << "baro" << YAML::Value;
    baro->EmitDrawn(y);
  }
  if (odometer) {
    y << YAML::Key << "odometer" << YAML::Value;
    odometer->EmitDrawn(y);
  }
  if (master) {
    y << YAML::Key << "master" << YAML::Value;
    master->EmitDrawn(y);
  }
  if (scenario.emit_trajectory) {
    y << YAML::Key << "trajectory" << YAML::Value;
    scenario.emit_trajectory(y);
  }
  y << YAML::Key << "init_errors" << YAML::Value << YAML::BeginMap;
  EmitVector(y, "position_ned_m", scenario.init_errors.position_ned_m);
  EmitVector(y, "velocity_ned_mps", scenario.init_errors.velocity_ned_mps);
  EmitVector(y, "attitude_phi_n_deg", scenario.init_errors.attitude_phi_n_rad, kDegToRad);
  y << YAML::EndMap << YAML::EndMap;
  errors.stream() << y.c_str() << "\n";

  // Commit only when everything was produced: a failure above leaves no file behind.
  imu_out.Commit();
  truth_out.Commit();
  init_out.Commit();
  if (angle_out) angle_out->Commit();
  if (temperature_out) temperature_out->Commit();
  if (gnss_out) gnss_out->Commit();
  if (mag_out) mag_out->Commit();
  if (baro_out) baro_out->Commit();
  if (odometer_out) odometer_out->Commit();
  if (master_out) master_out->Commit();
  errors.Commit();
  report.run_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

TemporarySimulation::TemporarySimulation(const Scenario& scenario, const SimulationOptions& options,
                                         const std::string& prefix) {
  const std::filesystem::path tmp = std::filesystem::temp_directory_path();
  std::string dir = (tmp / (prefix + "XXXXXX")).string();
  if (::mkdtemp(dir.data()) == nullptr) throw std::runtime_error("cannot create a temporary folder in " + tmp.string());
  dir_ = dir;
  try {
    report_ = Simulate(scenario, options, dir_);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
    throw;
  }
}

TemporarySimulation::~TemporarySimulation() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

}  // namespace navtwin::sim
