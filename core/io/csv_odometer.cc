#include "core/io/csv_odometer.h"

#include <cmath>
#include <stdexcept>

#include "core/io/csv_series.h"
#include "core/io/input_error.h"

namespace navtwin {
namespace {

constexpr double kMaxSpeed_mps = 200.0;

}  // namespace

std::vector<OdometerSample> ReadOdometerCsv(const std::string& path) {
  const ScalarSeries series =
      ReadScalarSeriesCsv(path, {SeriesColumn{"speed", {{"_mps", 1.0}}}, SeriesColumn{"distance", {{"_m", 1.0}}}});
  std::vector<OdometerSample> out;
  out.reserve(series.t_s.size());
  const bool speed = series.stem == "speed";
  for (std::size_t k = speed ? 0 : 1; k < series.t_s.size(); ++k) {
    OdometerSample s;
    if (speed) {
      s.t_s = series.t_s[k];
      s.speed_mps = series.value[k];
    } else {
      const double dt = series.t_s[k] - series.t_s[k - 1];
      s.t_s = series.t_s[k - 1] + 0.5 * dt;
      s.speed_mps = series.value[k] / dt;
    }
    if (std::abs(s.speed_mps) > kMaxSpeed_mps) {
      throw InputError(path, 0, speed ? "speed_mps" : "distance_m",
                       "a speed beyond 200 m/s at t = " + std::to_string(series.t_s[k]) + " s");
    }
    out.push_back(s);
  }
  if (out.empty()) throw InputError(path, 0, "distance_m", "one distance row gives no interval");
  return out;
}

CsvOdometerWriter::CsvOdometerWriter(const std::string& path) : file_(path) {
  file_.stream().precision(17);
  file_.stream() << "t_s,speed_mps\n";
}

void CsvOdometerWriter::Write(const OdometerSample& s) {
  if (!std::isfinite(s.t_s) || !std::isfinite(s.speed_mps)) {
    throw std::invalid_argument("CsvOdometerWriter: non-finite time or speed");
  }
  file_.stream() << s.t_s << ',' << s.speed_mps << '\n';
}

}  // namespace navtwin
