#include "problems/gnss_ins/scoring.h"

#include <cmath>
#include <stdexcept>

#include "core/earth.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

}  // namespace

struct TrajectoryScorer::Impl {
  std::unique_ptr<NavReader> nav_reader;
  std::unique_ptr<GnssReader> gnss_reader;
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();
  Intervals outages;
  std::vector<OutageDrift> drifts;  // one per outage, in order

  // The next reference epoch not yet compared.
  bool have_ref = false;
  bool ref_done = false;
  NavState ref_nav;
  GnssSample ref_gnss;

  bool have_previous = false;
  NavState previous;
  ScoreReport report;

  double RefTime() const { return nav_reader ? ref_nav.t_s : ref_gnss.t_s; }

  /// Makes have_ref true unless the reference is exhausted.
  bool Peek() {
    if (have_ref) return true;
    if (ref_done) return false;
    have_ref = nav_reader ? nav_reader->Next(&ref_nav) : gnss_reader->Next(&ref_gnss);
    ref_done = !have_ref;
    return have_ref;
  }

  NavError Compare(const NavState& s) const {
    if (nav_reader) return CompareNav(s, ref_nav);
    NavError e;
    e.t_s = s.t_s;
    // Antenna position of the solution, compared in the reference's local NED:
    // GeodeticToNed(p, ref) + R_n_b l_b (first order in the lever arm, exact enough for
    // lever arms of metres).
    e.pos_ned_m = wgs84::GeodeticToNed({s.lat_rad, s.lon_rad, s.h_m},
                                       {ref_gnss.lat_rad, ref_gnss.lon_rad, ref_gnss.h_m}) +
                  (s.q_n_b * lever_arm_b_m);
    if (ref_gnss.has_velocity) e.vel_ned_mps = s.v_n_mps - ref_gnss.v_n_mps;
    return e;
  }

  void Accumulate(const NavError& e) {
    report.all.Add(e);
    for (std::size_t k = 0; k < outages.size(); ++k) {
      if (e.t_s >= outages[k].first && e.t_s < outages[k].second) {
        report.inside.Add(e);
        OutageDrift& d = drifts[k];
        ++d.epochs;
        d.max_horizontal_m = std::max(d.max_horizontal_m, e.pos_ned_m.head<2>().norm());
        d.max_vertical_m = std::max(d.max_vertical_m, std::abs(e.pos_ned_m.z()));
        return;
      }
    }
    report.outside.Add(e);
  }

  void Add(const NavState& s) {
    if (have_previous && !(s.t_s > previous.t_s)) {
      throw std::invalid_argument("TrajectoryScorer: solution times must increase");
    }
    while (Peek() && RefTime() <= s.t_s + ins::kSameEpoch_s) {
      const double t = RefTime();
      if (std::abs(t - s.t_s) <= ins::kSameEpoch_s) {
        NavState at = s;
        at.t_s = t;
        Accumulate(Compare(at));
      } else if (have_previous && t >= previous.t_s - ins::kSameEpoch_s) {
        Accumulate(Compare(InterpolateNav(previous, s, t)));
      }  // else: before the solution starts
      if (gnss_reader && !ref_gnss.has_velocity) report.has_velocity = false;
      have_ref = false;
    }
    previous = s;
    have_previous = true;
  }
};

TrajectoryScorer::TrajectoryScorer(std::unique_ptr<NavReader> reference, Intervals outages)
    : impl_(std::make_unique<Impl>()) {
  impl_->nav_reader = std::move(reference);
  impl_->outages = std::move(outages);
  for (const auto& o : impl_->outages) impl_->drifts.push_back({o.first, o.second, 0, 0.0, 0.0});
}

TrajectoryScorer::TrajectoryScorer(std::unique_ptr<GnssReader> reference, Intervals outages,
                                   const Eigen::Vector3d& lever_arm_b_m)
    : impl_(std::make_unique<Impl>()) {
  impl_->gnss_reader = std::move(reference);
  impl_->lever_arm_b_m = lever_arm_b_m;
  impl_->outages = std::move(outages);
  impl_->report.has_attitude = false;
  for (const auto& o : impl_->outages) impl_->drifts.push_back({o.first, o.second, 0, 0.0, 0.0});
}

TrajectoryScorer::~TrajectoryScorer() = default;

void TrajectoryScorer::Add(const NavState& solution) { impl_->Add(solution); }

ScoreReport TrajectoryScorer::Report() const {
  ScoreReport r = impl_->report;
  if (r.all.count() == 0) r.has_velocity = impl_->nav_reader != nullptr;
  double sum_h = 0.0, sum_v = 0.0;
  for (const OutageDrift& d : impl_->drifts) {
    if (d.epochs == 0) continue;
    r.outages.push_back(d);
    sum_h += d.max_horizontal_m * d.max_horizontal_m;
    sum_v += d.max_vertical_m * d.max_vertical_m;
  }
  if (!r.outages.empty()) {
    r.outage_horizontal_rms_m = std::sqrt(sum_h / r.outages.size());
    r.outage_vertical_rms_m = std::sqrt(sum_v / r.outages.size());
  }
  return r;
}

std::unique_ptr<TrajectoryScorer> OpenReference(const std::string& path,
                                                TrajectoryScorer::Intervals outages,
                                                const Eigen::Vector3d& lever_arm_b_m) {
  const FileFormat format = DetectFormat(path);
  if (format == FileFormat::kRtklibPos || format == FileFormat::kKfginsGnss) {
    return std::make_unique<TrajectoryScorer>(OpenGnss(path), std::move(outages), lever_arm_b_m);
  }
  return std::make_unique<TrajectoryScorer>(OpenNav(path), std::move(outages));
}

}  // namespace navtwin::gnss_ins
