// Uses the installed headers and libraries: one second of pure inertial navigation at rest.
#include <cmath>
#include <cstdio>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/strapdown.h"

int main() {
  navtwin::NavState s;
  s.lat_rad = 0.7;
  navtwin::Strapdown ins(s);
  navtwin::ImuSample imu;
  imu.dt_s = 0.01;
  imu.dtheta_b_rad = navtwin::wgs84::EarthRateNed(s.lat_rad) * imu.dt_s;
  imu.dv_b_mps = -navtwin::wgs84::GravityNed(s.lat_rad, 0.0) * imu.dt_s;
  for (int k = 1; k <= 100; ++k) {
    imu.t_s = k * imu.dt_s;
    ins.Update(imu);
  }
  const double speed = ins.state().v_n_mps.norm();
  std::printf("speed after 1 s at rest: %g m/s\n", speed);
  return speed < 1e-9 ? 0 : 1;
}
