#include "problems/ins/demo_flight.h"

#include "core/io/kfgins.h"
#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"

namespace navtwin {

DemoFiles WriteDemoFlight(const std::string& dir, double rate_hz, double duration_s) {
  DemoFiles files{dir + "/imu.txt", dir + "/truth.nav"};
  KfginsImuWriter imu(files.imu_path);
  KfginsNavWriter truth(files.truth_path);
  const sim::DemoFlight flight;
  sim::SynthesizeImu(flight, {37.5 * kDegToRad, 127.0 * kDegToRad, 500.0}, rate_hz, duration_s,
                     [&](const ImuSample& sample, const NavState& state) {
                       if (sample.dt_s > 0.0) imu.Write(sample);
                       truth.Write(state);
                     });
  imu.Commit();
  truth.Commit();
  return files;
}

}  // namespace navtwin
