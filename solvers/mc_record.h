// What one Monte Carlo run of any problem returns (`navtwin mc`, docs/monte-carlo.md):
// per method, each estimated quantity's error (estimate - truth) at the points of an axis
// (time or distance) with the covariance the method reported there. A run is described by
// its record alone, so records can be computed on another thread or MPI rank, shipped as
// bytes (SerializeRunRecord) and reduced in run order on one process.
//
// The Cramér-Rao bound of a scenario uses the same shape: a method named "bound" whose
// covariances are the bound (its errors: those of the noise-free solution, near zero).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace navtwin::mc {

/// One estimated quantity of one method in one run, in SI units.
struct Quantity {
  std::string name;                     ///< e.g. "position_ned", "misalignment", "delay"
  std::string unit;                     ///< display unit, e.g. "m", "mrad", "ms"
  double scale = 1.0;                   ///< display value = SI value x scale
  std::string axis_name = "t_s";        ///< what the axis holds ("t_s", "distance_km", "final")
  std::vector<std::string> components;  ///< e.g. "n", "e", "d"; dim = components.size()
  std::vector<double> axis;             ///< the points, increasing
  std::vector<double> error;            ///< points x dim; NaN where the method has no estimate
  std::vector<double> covariance;       ///< points x dim x dim, row-major; NaN where unknown

  int dim() const { return static_cast<int>(components.size()); }
  int points() const { return static_cast<int>(axis.size()); }
  /// sqrt of the covariance's diagonal entry (component i at point p), SI; NaN when unknown.
  double Sigma(int point, int i) const {
    const int d = dim();
    return std::sqrt(covariance[(static_cast<std::size_t>(point) * d + i) * d + i]);
  }
  /// A quantity with `points` axis points, every error and covariance NaN.
  static Quantity Empty(std::string name, std::string unit, double scale, std::string axis_name,
                        std::vector<std::string> components, std::vector<double> axis);
  /// Sets point p's error and covariance (dim and dim x dim row-major).
  void Set(int point, const double* error_si, const double* covariance_si);
  /// Sets point p's error with a diagonal covariance diag(sigma^2).
  void SetDiagonal(int point, const double* error_si, const double* sigma_si);
};

struct MethodRecord {
  std::string method;
  std::string failure;     ///< why the method threw on this run; empty when it did not
  double run_time_s = 0.0; ///< wall time of the method on this run (not in result files)
  std::vector<Quantity> quantities;
};

struct RunRecord {
  int run = 0;
  std::uint64_t seed = 0;
  std::vector<MethodRecord> methods;
};

/// The axis of a time series: t0 + 1, t0 + 2, ... up to t_end (whole seconds; a
/// microsecond short of a whole second counts), or {t_end} when the span is under a second.
std::vector<double> WholeSecondGrid(double t0_s, double t_end_s);

/// Bytes of a record (host byte order: for ranks of one cluster) and back. Deserialize
/// throws std::runtime_error for bytes that are not a whole record.
std::string SerializeRunRecord(const RunRecord& record);
RunRecord DeserializeRunRecord(const std::string& bytes);

}  // namespace navtwin::mc
