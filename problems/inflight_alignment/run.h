// One entry point for the three methods of issue 7 and the figures its evidence needs:
// the heading track of a method against the distance flown, the error at given distances
// when a reference is known, and the JSON / table outputs of `navtwin inflight-align`.
#pragma once

#include <string>
#include <vector>

#include "problems/inflight_alignment/batch.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/filter.h"
#include "problems/inflight_alignment/free_ins.h"

namespace navtwin::inflight {

enum class Method { kDistance, kKalman, kBatch };
const char* MethodName(Method m);        ///< "distance", "kalman", "batch"
/// Parses a method name; throws std::invalid_argument listing the valid names.
Method ParseMethod(const std::string& name);

/// One point of a heading track (at a GPS fix).
struct HeadingPoint {
  double t_s = 0.0;
  double path_length_m = 0.0;
  double yaw_rad = 0.0;       ///< the method's heading
  double sigma_rad = 0.0;     ///< its 1 sigma
  double error_rad = 0.0;     ///< yaw - yaw_true wrapped to (-pi, pi]; NaN without truth
};

struct MethodResult {
  Method method = Method::kDistance;
  /// distance, kalman: the filter's heading after each fix (what it knew then).
  /// batch: the whole-flight smoothed heading (yaw_free - dH) at each fix.
  std::vector<HeadingPoint> track;
  /// The heading error at each of `at_km` (NaN when not reached or no truth). distance,
  /// kalman: the track's first point at or after the distance. batch: the batch solved
  /// on the fixes up to that point (what a batch run at that moment gives).
  std::vector<double> at_km;
  std::vector<double> error_at_km_rad;
  std::vector<double> sigma_at_km_rad;
  double final_error_rad = 0.0;  ///< NaN without truth
  double final_sigma_rad = 0.0;
  double run_time_s = 0.0;       ///< wall time of the method (simulation and reading excluded)
  /// Raw GPS fix sigma per horizontal axis (m): InflightSensorSpec::gps_sigma_m, or
  /// EstimateGpsSigma of the fixes when that is 0 (batch: the sigma its residuals used).
  double gps_sigma_m = 0.0;
  std::vector<HeadingComputation> computations;  ///< distance method
  BatchHeadingSolution batch;                    ///< batch method (whole flight)
  std::string note;              ///< e.g. GPS fixes rejected or down-weighted
};

/// Truth yaw at t (linear interpolation of the unwrapped yaw between truth records);
/// NaN outside the truth's span or without truth.
double TruthYawAt(const std::vector<NavState>& truth, double t_s);

/// Runs one method. at_km: distances for the error figures (default 10, 20, 50, 100).
MethodResult RunMethod(const InflightInputs& inputs, const InflightConfig& config, Method method,
                       const std::vector<double>& at_km = {10.0, 20.0, 50.0, 100.0});

/// `--format=json`: {"method":..,"heading_error_arcmin_at_km":{"10":..,..},
/// "final_heading_error_arcmin":..,"heading_sigma_arcmin":..,"run_time_s":..} plus
/// "heading_sigma_arcmin_at_km", "path_length_km", "gps_sigma_m" and method details;
/// NaN is written as null.
std::string MethodResultJson(const MethodResult& result);
/// Human-readable table: distance, heading error, sigma; then the final values.
std::string MethodResultTable(const MethodResult& result);
/// The track as CSV (t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin) for plots.
void WriteTrackCsv(const MethodResult& result, const std::string& path);

}  // namespace navtwin::inflight
