#include "problems/gnss_ins/sources.h"

#include <utility>
#include <vector>

#include "problems/ins/sources/baro.h"
#include "problems/ins/sources/gnss.h"
#include "problems/ins/sources/mag.h"
#include "problems/ins/sources/nhc.h"
#include "problems/ins/sources/odometer.h"
#include "problems/ins/sources/zupt.h"

namespace navtwin::gnss_ins {

ins::AidingSources MakeSources(const Inputs& inputs, const GnssInsConfig& config) {
  std::vector<double> fix_times_s;
  fix_times_s.reserve(inputs.gnss.size());
  for (const GnssSample& g : inputs.gnss) fix_times_s.push_back(g.t_s);
  ins::AidingSources sources;
  sources.push_back(ins::MakeGnssSource(inputs.gnss, config.gnss, config.installation.antenna_lever_arm_b_m,
                                        config.filter.gnss_reset_rejections, inputs.paths.gnss));
  sources.push_back(ins::MakeMagSource(inputs.mag, config.mag));
  sources.push_back(ins::MakeBaroSource(inputs.baro, config.baro, std::move(fix_times_s)));
  sources.push_back(ins::MakeZuptSource(config.zupt));
  if (config.nhc.enabled) sources.push_back(ins::MakeNhcSource(config.nhc, config.vehicle, config.zupt));
  if (config.odometer.enabled()) {
    sources.push_back(ins::MakeOdometerSource(inputs.odometer, config.odometer, config.vehicle));
  }
  return sources;
}

}  // namespace navtwin::gnss_ins
