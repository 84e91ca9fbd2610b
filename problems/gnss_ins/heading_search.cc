// Heading search over evenly spaced hypotheses (problems/gnss_ins/heading_search.h): the
// navigation filter (filter.h) run once per hypothesis over a window of the inputs.
#include "problems/gnss_ins/heading_search.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <sstream>
#include <stdexcept>

#include "core/io/input_error.h"
#include "core/rotation.h"
#include "problems/gnss_ins/filter.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

/// The GNSS kinds scored (filter.cc's keys of FilterResult::innovations).
const char* const kScoredKinds[] = {"gnss_position", "gnss_velocity"};

/// Median interval between consecutive GNSS epochs (outage gaps do not move it).
double MedianGnssInterval(const std::vector<GnssSample>& gnss) {
  std::vector<double> dt;
  dt.reserve(gnss.size());
  for (std::size_t i = 1; i < gnss.size(); ++i) dt.push_back(gnss[i].t_s - gnss[i - 1].t_s);
  if (dt.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

/// The samples of `all` with begin < t <= end.
template <typename Sample>
std::vector<Sample> Cut(const std::vector<Sample>& all, double begin_s, double end_s) {
  std::vector<Sample> out;
  for (const Sample& s : all) {
    if (s.t_s > end_s + ins::kSameEpoch_s) break;
    if (s.t_s > begin_s + ins::kSameEpoch_s) out.push_back(s);
  }
  return out;
}

}  // namespace

double HeadingSearchYawStd(int hypotheses) {
  if (hypotheses < 2) throw std::invalid_argument("HeadingSearchYawStd: at least 2 hypotheses");
  return M_PI / hypotheses;  // half of the spacing 2 pi / N
}

HeadingSearchResult SearchHeading(const Inputs& inputs, const GnssInsConfig& config,
                                  const std::function<InsState(double yaw_rad)>& state_for_yaw,
                                  std::ostream* progress) {
  const int n_hyp = config.init.heading_hypotheses;
  HeadingSearchResult result;
  result.yaw_std_rad = HeadingSearchYawStd(n_hyp);
  const double t0 = state_for_yaw(0.0).nav.t_s;
  result.window_begin_s = t0;

  // The window: the first round(heading_search_s / median interval) GNSS epochs after t0.
  const auto first = std::upper_bound(inputs.gnss.begin(), inputs.gnss.end(), t0 + ins::kSameEpoch_s,
                                      [](double t, const GnssSample& g) { return t < g.t_s; });
  const std::size_t available = static_cast<std::size_t>(inputs.gnss.end() - first);
  if (available == 0) {
    std::ostringstream reason;
    reason.precision(12);
    reason << "the heading search needs GNSS epochs after the alignment (it ends at t = " << t0 << " s)";
    throw InputError(inputs.paths.gnss, 0, "t", reason.str());
  }
  const double interval_s = MedianGnssInterval(inputs.gnss);
  std::size_t wanted = available;
  if (interval_s > 0.0) {
    wanted = static_cast<std::size_t>(std::max(1.0, std::round(config.init.heading_search_s / interval_s)));
  }
  result.gnss_epochs = std::min(wanted, available);
  result.window_end_s = first[result.gnss_epochs - 1].t_s;

  Inputs window;
  window.paths = inputs.paths;
  window.outages = inputs.outages;
  // The IMU from its start (RunFilter finds the sample holding t0) to the first sample
  // reaching the window's end (the filter processes a GNSS epoch inside a sample's
  // interval); measurements after t0 only, as the static start skips those at t0 (they
  // made the state).
  const std::vector<ImuSample>& head = inputs.imu.Head(result.window_end_s - ins::kSameEpoch_s);
  const auto imu_end = std::lower_bound(head.begin(), head.end(), result.window_end_s - ins::kSameEpoch_s,
                                        [](const ImuSample& s, double t) { return s.t_s < t; });
  window.imu = ins::ImuRecord(std::vector<ImuSample>(head.begin(), imu_end == head.end() ? imu_end : imu_end + 1));
  window.gnss = Cut(inputs.gnss, t0, result.window_end_s);
  window.mag = Cut(inputs.mag, t0, result.window_end_s);
  window.baro = Cut(inputs.baro, t0, result.window_end_s);

  if (progress != nullptr) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(1);
    line << "heading search: " << n_hyp << " hypotheses " << 360.0 / n_hyp << " deg apart (yaw std "
         << result.yaw_std_rad * kRadToDeg << " deg), " << result.gnss_epochs << " GNSS epochs " << t0 << " .. "
         << result.window_end_s << " s\n"
         << "heading search:   yaw [deg]      score  NIS/dof  rejected\n";
    *progress << line.str() << std::flush;
  }

  for (int k = 0; k < n_hyp; ++k) {
    HeadingHypothesis h;
    h.yaw_rad = WrapPi(2.0 * M_PI * k / n_hyp);
    GnssInsConfig c = config;
    c.init.source = InitConfig::Source::kGiven;
    c.init.heading = InitConfig::Heading::kAuto;
    c.init.state = state_for_yaw(h.yaw_rad);
    c.init.imu_errors = c.init.state->imu;
    c.init.std.att_rad.z() = result.yaw_std_rad;
    c.gnss.max_distance_m = std::numeric_limits<double>::infinity();
    try {
      const FilterResult run = RunFilter(window, c, false, nullptr, nullptr);
      double score = 0.0, nis = 0.0;
      int dof_accepted = 0;
      for (const char* kind : kScoredKinds) {
        const auto it = run.innovations.find(kind);
        if (it == run.innovations.end()) continue;
        const InnovationStats& s = it->second;
        score += s.nis_capped + s.log_det_s;
        h.updates += s.updates;
        h.rejected += s.rejected;
        nis += s.nis;
        dof_accepted += s.dof;
      }
      h.score = score;
      if (dof_accepted > 0) h.nis_per_dof = nis / dof_accepted;
    } catch (const std::exception& e) {
      // A wrong heading can drive its filter to a non-positive-definite innovation
      // covariance or non-finite states: that hypothesis is out.
      h.failure = e.what();
    }
    if (progress != nullptr) {
      char line[160];
      std::snprintf(line, sizeof(line), "heading search: %11.1f %10.1f %8.2f %5zu/%zu%s%s\n", h.yaw_rad * kRadToDeg,
                    h.score, h.nis_per_dof, h.rejected, h.updates, h.failure.empty() ? "" : "  failed: ",
                    h.failure.c_str());
      *progress << line << std::flush;
    }
    result.hypotheses.push_back(std::move(h));
  }

  for (std::size_t i = 1; i < result.hypotheses.size(); ++i) {
    if (result.hypotheses[i].score < result.hypotheses[result.best].score) result.best = i;
  }
  const HeadingHypothesis& best = result.hypotheses[result.best];
  if (!std::isfinite(best.score)) {
    throw std::runtime_error("heading search: every hypothesis' filter failed (first: " +
                             result.hypotheses.front().failure + ")");
  }
  if (progress != nullptr) {
    std::size_t second = result.best == 0 ? 1 : 0;
    for (std::size_t i = 0; i < result.hypotheses.size(); ++i) {
      if (i != result.best && result.hypotheses[i].score < result.hypotheses[second].score) second = i;
    }
    char line[200];
    std::snprintf(line, sizeof(line),
                  "heading search: chosen yaw %.1f deg (score %.1f; next best %.1f deg, score %+.1f higher)\n",
                  best.yaw_rad * kRadToDeg, best.score, result.hypotheses[second].yaw_rad * kRadToDeg,
                  result.hypotheses[second].score - best.score);
    *progress << line << std::flush;
  }
  return result;
}

}  // namespace navtwin::gnss_ins
