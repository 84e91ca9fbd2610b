// Heading search for a static alignment that has no heading reference: a consumer MEMS
// gyro cannot gyrocompass (its bias is far above the Earth rate) and there may be no
// magnetometer, or the device may be held at an unknown angle to the direction of travel
// (so the GNSS course is not the heading either). Roll and pitch come from the static
// alignment; the heading is found as in multiple-model adaptive estimation: one filter per
// heading hypothesis runs over the first GNSS data after the alignment, and the
// hypothesis whose GNSS innovations are the most likely wins (docs/gnss-ins.md "Heading
// search").
//
// Score of a hypothesis: the innovations' -2 log-likelihood (the constant m log 2 pi
// dropped), over the window's GNSS position and velocity updates,
//   score = sum_k [ min(NIS_k, gate_k) + log det S_k ],   S_k = H P H^T + I (whitened).
// The log det S term matters: a filter led astray by a wrong heading inflates its
// covariance, which shrinks its NIS; NIS alone would reward that. The cap makes an update
// rejected by the chi-square gate cost exactly the gate (the penalty for a rejection),
// so one outlier cannot outweigh the rest. Only GNSS updates are scored: the window has
// the same GNSS epochs for every hypothesis, while ZUPTs depend on each filter's
// bias-corrected IMU samples.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/inputs.h"

namespace navtwin::gnss_ins {

/// The initial heading std with `hypotheses` evenly spaced headings: half their spacing,
/// pi / hypotheses. The nearest hypothesis is at most half a spacing from the true heading,
/// so the worst case is a 1-sigma error (the uniform distribution's std, spacing / sqrt(12),
/// would make it 1.7 sigma, beyond what the linearised filter corrects reliably).
double HeadingSearchYawStd(int hypotheses);

struct HeadingHypothesis {
  double yaw_rad = 0.0;
  /// See the file comment; +infinity when the hypothesis' filter failed (`failure`).
  double score = std::numeric_limits<double>::infinity();
  std::size_t updates = 0;   ///< GNSS position and velocity updates in the window
  std::size_t rejected = 0;  ///< of which rejected by the chi-square gate
  double nis_per_dof = std::numeric_limits<double>::quiet_NaN();  ///< accepted updates' mean NIS / m
  std::string failure;       ///< why the filter failed (empty: it ran)
};

struct HeadingSearchResult {
  /// yaw = k 2 pi / N wrapped to (-pi, pi], k = 0 .. N-1 (N = init.heading_hypotheses).
  std::vector<HeadingHypothesis> hypotheses;
  std::size_t best = 0;        ///< the smallest score (the first of equal ones)
  double yaw_std_rad = 0.0;    ///< HeadingSearchYawStd(N)
  double window_begin_s = 0.0; ///< the filters' start (the alignment's end)
  double window_end_s = 0.0;   ///< the last GNSS epoch scored
  std::size_t gnss_epochs = 0; ///< GNSS epochs in (window_begin_s, window_end_s]
};

/// Runs one filter (RunFilter without RTS) per heading hypothesis, each from
/// state_for_yaw(yaw) (at its nav.t_s, with the IMU errors in it) with the initial std of
/// config.init.std but the heading's HeadingSearchYawStd(N), over the GNSS epochs after the
/// start that make config.init.heading_search_s of data (round(heading_search_s / median
/// GNSS interval) epochs; outages do not count), and scores each (file comment). The
/// hypotheses' filters do not stop on gnss.max_distance_m (a wrong heading may drift far).
/// Reports the window, each hypothesis' score and the choice on `progress` if not null.
/// Throws InputError (GNSS file) when no GNSS epoch follows the start, std::runtime_error
/// when every hypothesis' filter failed, std::invalid_argument for fewer than 2 hypotheses.
HeadingSearchResult SearchHeading(const Inputs& inputs, const GnssInsConfig& config,
                                  const std::function<InsState(double yaw_rad)>& state_for_yaw,
                                  std::ostream* progress);

}  // namespace navtwin::gnss_ins
