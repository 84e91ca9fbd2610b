// The vehicle constraints on the simulated MEMS car (preset mems-car-odometer, whose motion
// obeys the non-holonomic constraint exactly at the IMU): through a 60 s GNSS outage the
// NHC bounds the horizontal drift of the filter, the RTS smoother and the batch, and it
// stays off while the car stands still; the odometer bounds the along-track error too,
// and filter, RTS and batch estimate its scale factor.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/units.h"
#include "core/sim/presets.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/filter.h"
#include "tests/problems/gnss_ins/sim_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_vehicle_test {

using test_records::TruthAt;

// One 300 s lap of the preset: the outage covers the first turn and the S-bends.
constexpr double kEnd_s = 300.0;
constexpr double kOutageStart_s = 90.0;  // after the first IMU epoch
constexpr double kOutageLen_s = 60.0;

/// The preset simulated once (seed 7) into a folder kept for the suite.
class Car : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string dir = ::testing::TempDir() + "navtwin_car_XXXXXX";
    ASSERT_NE(::mkdtemp(dir.data()), nullptr);
    dir_ = new std::string(dir);
    sim::SimulationOptions options;
    options.seed = 7;
    sim::Simulate(sim::LoadScenario("mems-car-odometer"), options, dir);
    truth_ = new std::vector<NavState>(test_records::ReadAll<NavState>(OpenNav(dir + "/truth.nav")));
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete truth_;
    delete dir_;
  }

  /// The preset's specification as a user writes it, GNSS outage included.
  static GnssInsConfig Config() {
    GnssInsConfig c;
    c.imu_noise.gyro_arw_rad_per_sqrt_s = 0.3 * kDegPerSqrtHour_radpsqrts;
    c.imu_noise.accel_vrw_mps_per_sqrt_s = 0.1 * kMpsPerSqrtHour_mpspsqrts;
    c.imu_noise.gyro_bias_std_radps = 10.0 * kDegPerHour_radps;
    c.imu_noise.accel_bias_std_mps2 = 2.0 * kMilliG_mps2;
    c.imu_noise.correlation_time_s = INFINITY;
    c.installation.antenna_lever_arm_b_m = Eigen::Vector3d(0.0, 0.0, -1.0);
    c.init.source = InitConfig::Source::kGiven;
    c.init.state = InsState{test_records::ReadAll<NavState>(OpenNav(*dir_ + "/init.nav")).front(), ImuErrors{}};
    c.init.std.pos_ned_m = Eigen::Vector3d(2.0, 2.0, 3.0);
    c.init.std.vel_ned_mps.setConstant(0.1);
    c.init.std.att_rad = Eigen::Vector3d(1.0, 1.0, 3.0) * kDegToRad;
    c.end_time_s = kEnd_s;
    c.outages.start_s = kOutageStart_s;
    c.outages.len_s = kOutageLen_s;
    return c;
  }

  static Inputs Load(const GnssInsConfig& c) {
    InputPaths paths;
    paths.imu = *dir_ + "/imu.txt";
    paths.gnss = *dir_ + "/gnss.txt";
    return LoadInputs(paths, c);
  }

  /// Largest horizontal position error of a solution's epochs inside the outage.
  static double OutageDrift_m(const Solution& s, const Inputs& in) {
    double worst = 0.0;
    for (const NavEpoch& e : s.epochs) {
      const double t = e.state.nav.t_s;
      if (t < in.outages.front().first || t >= in.outages.front().second) continue;
      const NavState truth = TruthAt(*truth_, t);
      const Eigen::Vector3d d = wgs84::GeodeticToNed({e.state.nav.lat_rad, e.state.nav.lon_rad, e.state.nav.h_m},
                                                     {truth.lat_rad, truth.lon_rad, truth.h_m});
      worst = std::max(worst, d.head<2>().norm());
    }
    return worst;
  }

  static std::string* dir_;
  static std::vector<NavState>* truth_;
};
std::string* Car::dir_ = nullptr;
std::vector<NavState>* Car::truth_ = nullptr;

TEST_F(Car, NonHolonomicConstraintBoundsTheOutageDrift) {
  GnssInsConfig free = Config();
  GnssInsConfig nhc = Config();
  nhc.nhc.enabled = true;
  const Inputs in = Load(free);
  ASSERT_EQ(in.outages.size(), 1u);
  const FilterResult a = RunFilter(in, free, true, {}, nullptr);
  const FilterResult b = RunFilter(in, nhc, true, {}, nullptr);
  const Solution batch_a = RunBatch(in, free, *a.rts, nullptr);
  const Solution batch_b = RunBatch(in, nhc, *b.rts, nullptr);
  const double filter_free = OutageDrift_m(a.filter, in), filter_nhc = OutageDrift_m(b.filter, in);
  const double rts_free = OutageDrift_m(*a.rts, in), rts_nhc = OutageDrift_m(*b.rts, in);
  const double batch_free = OutageDrift_m(batch_a, in), batch_nhc = OutageDrift_m(batch_b, in);
  std::cout << "outage drift [m] without / with NHC: filter " << filter_free << " / " << filter_nhc << ", RTS "
            << rts_free << " / " << rts_nhc << ", batch " << batch_free << " / " << batch_nhc << "\n";
  // A 10 deg/h, 2 mg MEMS IMU drifts tens of metres in 60 s of free inertial navigation;
  // the constraint removes the lateral and vertical velocity error, so what remains in the
  // filter is the along-track error: at least three times smaller. The smoothers bridge the
  // outage from both ends (about a metre without the constraint); NHC still lowers it.
  EXPECT_GT(filter_free, 10.0);
  EXPECT_LT(filter_nhc, filter_free / 3.0);
  EXPECT_LT(rts_nhc, rts_free);
  EXPECT_LT(batch_nhc, batch_free);
  // NHC updates happen once a second while moving, none while the car stands (the first
  // 20 s and the last 25 s of the lap): one per second of the 255 s of motion.
  const MeasurementCount& used = b.filter.counts.at("nhc");
  EXPECT_GT(used.used + used.rejected, 240u);
  EXPECT_LT(used.used + used.rejected, 260u);
  EXPECT_GT(batch_b.counts.at("nhc").used, 0u);
}

TEST_F(Car, OdometerBoundsTheAlongTrackDriftAndItsScaleFactorIsEstimated) {
  GnssInsConfig nhc = Config();
  nhc.nhc.enabled = true;
  GnssInsConfig odo = nhc;
  odo.odometer.file = *dir_ + "/odometer.csv";
  const Inputs in = Load(odo);  // the NHC-only run leaves the odometer samples unused
  const FilterResult a = RunFilter(in, nhc, true, {}, nullptr);
  const FilterResult b = RunFilter(in, odo, true, {}, nullptr);
  const Solution batch = RunBatch(in, odo, *b.rts, nullptr);
  const double filter_nhc = OutageDrift_m(a.filter, in), filter_odo = OutageDrift_m(b.filter, in);
  std::cout << "outage drift [m] NHC / NHC + odometer: filter " << filter_nhc << " / " << filter_odo << ", RTS "
            << OutageDrift_m(*a.rts, in) << " / " << OutageDrift_m(*b.rts, in) << ", batch "
            << OutageDrift_m(batch, in) << "\n";
  // The odometer measures the along-track speed that NHC leaves free.
  EXPECT_LT(filter_odo, filter_nhc);
  // The scale factor (5000 ppm in the preset) as the filter ends, the RTS and the batch
  // estimate it: each within 3 of its own sigma, and each sigma below 1000 ppm.
  const double truth = 5e-3;
  for (const NavEpoch* e : {&b.filter.epochs.back(), &b.rts->epochs.front(), &batch.epochs.front()}) {
    ASSERT_EQ(e->aux.size(), 1);
    ASSERT_EQ(e->aux_std.size(), 1);
    std::cout << "odometer scale " << e->aux[0] * 1e6 << " +- " << e->aux_std[0] * 1e6 << " ppm\n";
    EXPECT_LT(std::abs(e->aux[0] - truth), 3.0 * e->aux_std[0]);
    EXPECT_LT(e->aux_std[0], 1e-3);
  }
  EXPECT_GT(b.filter.counts.at("odometer").used, 2500u);  // 10 Hz over the 300 s lap
  EXPECT_GT(batch.counts.at("odometer").used, 200u);      // at the batch's states
}

}  // namespace gnss_ins_vehicle_test
}  // namespace navtwin::gnss_ins
