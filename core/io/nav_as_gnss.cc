#include "core/io/nav_as_gnss.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace navtwin {
namespace {

void RequireFixSigma(double sigma, const char* name) {
  if (!(std::isfinite(sigma) && sigma > 0.0)) {
    throw std::invalid_argument(std::string("NavAsGnssReader: ") + name + " must be > 0 and finite, got " +
                                std::to_string(sigma));
  }
}

class NavAsGnss final : public GnssReader {
 public:
  NavAsGnss(std::unique_ptr<NavReader> nav, const NavAsGnssOptions& options)
      : nav_(std::move(nav)), options_(options) {}

  bool Next(GnssSample* sample) override {
    NavState s;
    if (!nav_->Next(&s)) return false;
    GnssSample g;
    g.t_s = s.t_s;
    g.gps_week = s.gps_week;
    g.lat_rad = s.lat_rad;
    g.lon_rad = s.lon_rad;
    g.h_m = s.h_m;
    g.pos_std_ned_m.setConstant(options_.pos_sigma_m);
    g.has_velocity = true;
    g.v_n_mps = s.v_n_mps;
    g.vel_std_ned_mps.setConstant(options_.vel_sigma_mps);
    *sample = g;
    return true;
  }
  const std::string& path() const override { return nav_->path(); }

 private:
  std::unique_ptr<NavReader> nav_;
  NavAsGnssOptions options_;
};

}  // namespace

std::unique_ptr<GnssReader> NavAsGnssReader(std::unique_ptr<NavReader> nav, const NavAsGnssOptions& options) {
  RequireFixSigma(options.pos_sigma_m, "pos_sigma_m");
  RequireFixSigma(options.vel_sigma_mps, "vel_sigma_mps");
  return std::make_unique<NavAsGnss>(std::move(nav), options);
}

}  // namespace navtwin
