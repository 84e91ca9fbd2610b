#include "problems/gnss_ins/scoring.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/earth.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

using Sigmas = std::array<double, kScoredComponents>;

/// The sigmas of the compared components from the error-state std at an epoch, linear
/// between std_a and std_b at weight w (the same vector twice at a solution epoch), with
/// the solution's attitude q_n_b for the roll/pitch mapping (scoring.h); NaN without std.
Sigmas ComparedSigmas(const Eigen::VectorXd& std_a, const Eigen::VectorXd& std_b, double w,
                      const Eigen::Quaterniond& q_n_b) {
  Sigmas s;
  s.fill(ScoredEpoch::kNaN);
  if (std_a.size() < err::kAtt + 3 || std_b.size() != std_a.size()) return s;
  double sd[kScoredComponents];
  for (int i = 0; i < kScoredComponents; ++i) sd[i] = (1.0 - w) * std_a[i] + w * std_b[i];
  for (int i = 0; i < err::kAtt; ++i) s[i] = sd[i];
  const double psi = EulerFromQuat(q_n_b).z();
  const double c2 = std::cos(psi) * std::cos(psi), s2 = std::sin(psi) * std::sin(psi);
  const double var_n = sd[err::kAtt] * sd[err::kAtt], var_e = sd[err::kAtt + 1] * sd[err::kAtt + 1];
  s[6] = std::sqrt(c2 * var_n + s2 * var_e);
  s[7] = std::sqrt(s2 * var_n + c2 * var_e);
  s[8] = sd[err::kAtt + 2];
  return s;
}

}  // namespace

double ScoredEpoch::CombinedStd(int c) const {
  const double ref = std::isnan(ref_std[c]) ? 0.0 : ref_std[c];
  return std::sqrt(sol_std[c] * sol_std[c] + ref * ref);
}

void ConsistencyStats::Add(const ScoredEpoch& e) {
  ++epochs_;
  double nees = 0.0;
  int nees_terms = 0;
  for (int c = 0; c < kScoredComponents; ++c) {
    if (!std::isfinite(e.err[c])) continue;
    const double sigma = e.CombinedStd(c);
    if (!(sigma > 0.0) || !std::isfinite(sigma)) {
      ++missing_[c];
      continue;
    }
    const double r = e.err[c] / sigma;
    sum_sq_[c] += r * r;
    ++count_[c];
    if (c < 3) {
      nees += r * r;
      ++nees_terms;
    }
  }
  if (nees_terms == 3) {
    nees_sum_ += nees;
    ++nees_count_;
  }
}

double ConsistencyStats::RmsRatio(int c) const {
  return count_[c] ? std::sqrt(sum_sq_[c] / count_[c]) : std::numeric_limits<double>::quiet_NaN();
}

double ConsistencyStats::PosNeesMean() const {
  return nees_count_ ? nees_sum_ / nees_count_ : std::numeric_limits<double>::quiet_NaN();
}

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
  Eigen::VectorXd previous_std;  // assigned in place: no allocation per solution epoch
  ScoreReport report;
  std::function<void(const ScoredEpoch&)> sink;

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

  /// The errors and sigmas of one compared epoch, NaN where the reference lacks a component.
  ScoredEpoch Scored(const NavError& e, const Sigmas& sol_std) const {
    ScoredEpoch se;
    se.t_s = e.t_s;
    se.sol_std = sol_std;
    for (int i = 0; i < 3; ++i) se.err[i] = e.pos_ned_m[i];
    const bool velocity = nav_reader || ref_gnss.has_velocity;
    for (int i = 0; i < 3 && velocity; ++i) se.err[3 + i] = e.vel_ned_mps[i];
    for (int i = 0; i < 3 && nav_reader; ++i) se.err[6 + i] = e.rpy_rad[i];
    if (gnss_reader) {
      for (int i = 0; i < 3; ++i) se.ref_std[i] = ref_gnss.pos_std_ned_m[i];
      for (int i = 0; i < 3 && velocity; ++i) se.ref_std[3 + i] = ref_gnss.vel_std_ned_mps[i];
    }
    return se;
  }

  /// The solution `s` (at the reference time) with the sigmas of its errors.
  void Accumulate(const NavState& s, const Sigmas& sol_std) {
    const NavError e = Compare(s);
    ScoredEpoch se = Scored(e, sol_std);
    report.all.Add(e);
    report.consistency_all.Add(se);
    bool inside = false;
    for (std::size_t k = 0; k < outages.size() && !inside; ++k) {
      if (e.t_s >= outages[k].first && e.t_s < outages[k].second) {
        inside = true;
        OutageDrift& d = drifts[k];
        ++d.epochs;
        d.max_horizontal_m = std::max(d.max_horizontal_m, e.pos_ned_m.head<2>().norm());
        d.max_vertical_m = std::max(d.max_vertical_m, std::abs(e.pos_ned_m.z()));
      }
    }
    se.in_outage = inside;
    (inside ? report.inside : report.outside).Add(e);
    (inside ? report.consistency_inside : report.consistency_outside).Add(se);
    if (sink) sink(se);
  }

  void Add(const NavEpoch& epoch) {
    const NavState& s = epoch.state.nav;
    if (have_previous && !(s.t_s > previous.t_s)) {
      throw std::invalid_argument("TrajectoryScorer: solution times must increase");
    }
    while (Peek() && RefTime() <= s.t_s + ins::kSameEpoch_s) {
      const double t = RefTime();
      if (std::abs(t - s.t_s) <= ins::kSameEpoch_s) {
        NavState at = s;
        at.t_s = t;
        Accumulate(at, ComparedSigmas(epoch.std, epoch.std, 0.0, at.q_n_b));
      } else if (have_previous && t >= previous.t_s - ins::kSameEpoch_s) {
        const NavState at = InterpolateNav(previous, s, t);
        // The weight InterpolateNav uses.
        const double w = (t - previous.t_s) / (s.t_s - previous.t_s);
        Accumulate(at, ComparedSigmas(previous_std, epoch.std, w, at.q_n_b));
      }  // else: before the solution starts
      if (gnss_reader && !ref_gnss.has_velocity) report.has_velocity = false;
      have_ref = false;
    }
    previous = s;
    previous_std = epoch.std;
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
  impl_->report.reference_has_std = true;
  for (const auto& o : impl_->outages) impl_->drifts.push_back({o.first, o.second, 0, 0.0, 0.0});
}

TrajectoryScorer::~TrajectoryScorer() = default;

void TrajectoryScorer::Add(const NavEpoch& solution) { impl_->Add(solution); }

void TrajectoryScorer::OnEpoch(std::function<void(const ScoredEpoch&)> sink) { impl_->sink = std::move(sink); }

bool TrajectoryScorer::reference_has_std() const { return impl_->gnss_reader != nullptr; }

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
