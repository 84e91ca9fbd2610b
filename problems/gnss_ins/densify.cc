#include "problems/gnss_ins/densify.h"

#include <cmath>
#include <memory>
#include <vector>

#include "core/imu_split.h"
#include "core/rotation.h"
#include "core/strapdown.h"

namespace navtwin::gnss_ins {
namespace {

/// Times closer than this are the same epoch (knots placed on IMU time tags).
constexpr double kTimeTol_s = 1e-9;

/// (1 - w) a + w b where the sizes agree, else empty; `out` keeps its storage.
void BlendVector(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double w, Eigen::VectorXd* out) {
  if (a.size() == b.size()) {
    *out = (1.0 - w) * a + w * b;
  } else {
    out->resize(0);
  }
}

/// IMU errors, std and auxiliary states of knots a and b blended at weight w into `e`
/// (its vectors reused: no allocation per IMU epoch).
void BlendInto(const NavEpoch& a, const NavEpoch& b, double w, NavEpoch* e) {
  e->state.imu.bg_radps = (1.0 - w) * a.state.imu.bg_radps + w * b.state.imu.bg_radps;
  e->state.imu.ba_mps2 = (1.0 - w) * a.state.imu.ba_mps2 + w * b.state.imu.ba_mps2;
  e->state.imu.sg = (1.0 - w) * a.state.imu.sg + w * b.state.imu.sg;
  e->state.imu.sa = (1.0 - w) * a.state.imu.sa + w * b.state.imu.sa;
  BlendVector(a.std, b.std, w, &e->std);
  BlendVector(a.aux, b.aux, w, &e->aux);
  BlendVector(a.aux_std, b.aux_std, w, &e->aux_std);
}

}  // namespace

bool OutputDecimator::Take(double t_s) {
  if (rate_hz_ <= 0.0) return true;
  // The 1e-6 tick guards against t * rate landing just below an integer by rounding.
  const long long tick = static_cast<long long>(std::floor(t_s * rate_hz_ + 1e-6));
  if (first_ || tick != last_tick_) {
    first_ = false;
    last_tick_ = tick;
    return true;
  }
  return false;
}

void Densify(const Solution& solution, const Inputs& inputs, const std::function<void(const NavEpoch&)>& output) {
  const std::vector<NavEpoch>& knots = solution.epochs;
  if (knots.empty()) return;
  const std::size_t n_knots = knots.size();
  Strapdown mech(knots[0].state.nav);
  std::size_t j = 0;  // mechanizing from knot j
  // Mechanized states at the IMU epochs of the current interval, waiting for the
  // mismatch at knot j + 1.
  std::vector<NavState> pending;
  NavEpoch e;  // the epoch handed to `output`, reused

  // Knot j + 1 reached with the mechanized state `m`: correct and emit the pending
  // epochs, restart from the knot.
  auto finish_interval = [&](const NavState& m) {
    const NavEpoch& a = knots[j];
    const NavEpoch& b = knots[j + 1];
    const NavState& k = b.state.nav;
    const double dlat = k.lat_rad - m.lat_rad;
    const double dlon = WrapPi(k.lon_rad - m.lon_rad);
    const double dh = k.h_m - m.h_m;
    const Eigen::Vector3d dv = k.v_n_mps - m.v_n_mps;
    const Eigen::Vector3d phi = AttitudeError(k.q_n_b, m.q_n_b);
    const double span = b.state.nav.t_s - a.state.nav.t_s;
    for (const NavState& p : pending) {
      const double w = span > 0.0 ? (p.t_s - a.state.nav.t_s) / span : 1.0;
      BlendInto(a, b, w, &e);
      e.state.nav = p;
      e.state.nav.lat_rad = p.lat_rad + w * dlat;
      e.state.nav.lon_rad = WrapPi(p.lon_rad + w * dlon);
      e.state.nav.h_m = p.h_m + w * dh;
      e.state.nav.v_n_mps = p.v_n_mps + w * dv;
      e.state.nav.q_n_b = ApplyAttitudeError(Eigen::Vector3d(w * phi), p.q_n_b);
      output(e);
    }
    pending.clear();
    ++j;
    NavState restart = k;
    restart.gps_week = m.gps_week;
    mech.SetState(restart);
  };

  const double t_first = knots[0].state.nav.t_s;
  const std::unique_ptr<ImuReader> imu = inputs.imu.Read();
  ImuSample s;
  while (imu->Next(&s)) {
    if (s.t_s <= t_first + kTimeTol_s) continue;
    ImuSample piece = s;
    if (piece.t_s - piece.dt_s < t_first - kTimeTol_s) piece = SplitImuSample(piece, t_first).second;
    // Knots strictly inside this sample's interval: mechanize up to each and restart.
    while (j + 1 < n_knots && piece.t_s > knots[j + 1].state.nav.t_s + kTimeTol_s) {
      const double tk = knots[j + 1].state.nav.t_s;
      if (tk > piece.t_s - piece.dt_s + kTimeTol_s) {
        const auto parts = SplitImuSample(piece, tk);
        mech.Update(CorrectImu(parts.first, knots[j].state.imu));
        piece = parts.second;
      }
      finish_interval(mech.state());
    }
    mech.Update(CorrectImu(piece, knots[j].state.imu));
    if (j + 1 < n_knots) {
      pending.push_back(mech.state());
      if (std::abs(s.t_s - knots[j + 1].state.nav.t_s) <= kTimeTol_s) finish_interval(mech.state());
    } else {
      // Past the last knot: free mechanization with the last knot's IMU errors and std.
      e = knots.back();
      e.state.nav = mech.state();
      output(e);
    }
  }
}

}  // namespace navtwin::gnss_ins
