#include "problems/gnss_ins/output.h"

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/io/text_line.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::gnss_ins {
namespace {

/// One CSV row, numbers in the shortest form that reads back exactly (TextLine: the
/// files have a row per IMU epoch, so stream formatting would dominate the run).
void Row(std::ostream& out, double t_s, const double* values, int n) {
  TextLine line;
  line.Number(t_s);
  for (int i = 0; i < n; ++i) line.Char(',').Number(values[i]);
  line.Char('\n').WriteTo(out);
}

/// A number, or "nan" for any NaN (whatever its sign bit).
void NumberOrNan(TextLine& line, double x) {
  if (std::isnan(x)) {
    line.Char('n').Char('a').Char('n');
  } else {
    line.Number(x);
  }
}

}  // namespace

const char* const NavOutputWriter::kFiles[4] = {"nav.nav", "nav.csv", "std.csv", "imu_errors.csv"};

NavOutputWriter::NavOutputWriter(const std::string& dir, bool scale_factors)
    : scale_factors_(scale_factors),
      nav_(dir + "/" + kFiles[0]),
      csv_(dir + "/" + kFiles[1]),
      std_(dir + "/" + kFiles[2]),
      errors_(dir + "/" + kFiles[3]) {
  csv_.stream() << "t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg\n";
  std_.stream() << "t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,"
                   "vel_d_std_mps,att_n_std_deg,att_e_std_deg,att_d_std_deg,bg_x_std_deg_h,"
                   "bg_y_std_deg_h,bg_z_std_deg_h,ba_x_std_mg,ba_y_std_mg,ba_z_std_mg";
  if (scale_factors_) {
    std_.stream() << ",sg_x_std_ppm,sg_y_std_ppm,sg_z_std_ppm,sa_x_std_ppm,sa_y_std_ppm,sa_z_std_ppm";
  }
  std_.stream() << '\n';
  errors_.stream() << "t_s,bg_x_deg_h,bg_y_deg_h,bg_z_deg_h,ba_x_mg,ba_y_mg,ba_z_mg";
  if (scale_factors_) errors_.stream() << ",sg_x_ppm,sg_y_ppm,sg_z_ppm,sa_x_ppm,sa_y_ppm,sa_z_ppm";
  errors_.stream() << '\n';
}

void NavOutputWriter::Write(const NavEpoch& epoch) {
  const NavState& s = epoch.state.nav;
  nav_.Write(s);  // checks the state is finite (std::invalid_argument otherwise)
  const Eigen::Vector3d rpy_deg = EulerFromQuat(s.q_n_b) * kRadToDeg;
  const double nav[9] = {s.lat_rad * kRadToDeg, s.lon_rad * kRadToDeg, s.h_m,
                         s.v_n_mps.x(),         s.v_n_mps.y(),         s.v_n_mps.z(),
                         rpy_deg.x(),           rpy_deg.y(),           rpy_deg.z()};
  Row(csv_.stream(), s.t_s, nav, 9);

  // Standard deviations in the units of the header; NaN where not computed.
  const int n = scale_factors_ ? err::kSize21 : err::kSize15;
  double sd[err::kSize21];
  for (int i = 0; i < n; ++i) {
    double scale = 1.0;
    if (i >= err::kAtt && i < err::kBg) scale = kRadToDeg;
    if (i >= err::kBg && i < err::kBa) scale = 1.0 / kDegPerHour_radps;
    if (i >= err::kBa && i < err::kSg) scale = 1.0 / kMilliG_mps2;
    if (i >= err::kSg) scale = 1.0 / kPpm;
    sd[i] = i < epoch.std.size() ? epoch.std[i] * scale : std::numeric_limits<double>::quiet_NaN();
  }
  Row(std_.stream(), s.t_s, sd, n);

  const ImuErrors& e = epoch.state.imu;
  double imu[12];
  for (int i = 0; i < 3; ++i) {
    imu[i] = e.bg_radps[i] / kDegPerHour_radps;
    imu[3 + i] = e.ba_mps2[i] / kMilliG_mps2;
    imu[6 + i] = e.sg[i] / kPpm;
    imu[9 + i] = e.sa[i] / kPpm;
  }
  Row(errors_.stream(), s.t_s, imu, scale_factors_ ? 12 : 6);
  ++count_;
}

void NavOutputWriter::Commit() {
  nav_.Commit();
  csv_.Commit();
  std_.Commit();
  errors_.Commit();
}

ErrorsCsvWriter::ErrorsCsvWriter(const std::string& out_dir, const std::string& method, bool reference_std)
    : dir_(out_dir + "/" + method), path_(dir_ + "/errors.csv"), reference_std_(reference_std) {
  struct stat st;
  if (::stat(dir_.c_str(), &st) != 0) {
    if (::mkdir(dir_.c_str(), 0755) != 0) throw std::runtime_error("cannot create the folder " + dir_);
    created_dir_ = true;
  } else if (!S_ISDIR(st.st_mode)) {
    throw std::runtime_error(dir_ + " exists and is not a folder");
  }
  try {
    file_ = std::make_unique<AtomicFile>(path_);
  } catch (...) {
    if (created_dir_) ::rmdir(dir_.c_str());
    throw;
  }
  std::ostream& out = file_->stream();
  out << "t_s,pos_n_err_m,pos_e_err_m,pos_d_err_m,vel_n_err_mps,vel_e_err_mps,vel_d_err_mps,roll_err_deg,"
         "pitch_err_deg,yaw_err_deg,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,"
         "vel_d_std_mps,roll_std_deg,pitch_std_deg,yaw_std_deg,in_outage";
  if (reference_std_) {
    out << ",ref_pos_n_std_m,ref_pos_e_std_m,ref_pos_d_std_m,ref_vel_n_std_mps,ref_vel_e_std_mps,ref_vel_d_std_mps";
  }
  out << '\n';
}

ErrorsCsvWriter::~ErrorsCsvWriter() {
  file_.reset();  // removes the temporary unless committed
  if (created_dir_ && !committed_) ::rmdir(dir_.c_str());
}

void ErrorsCsvWriter::Write(const ScoredEpoch& e) {
  TextLine line;
  line.Number(e.t_s);
  for (int c = 0; c < kScoredComponents; ++c) NumberOrNan(line.Char(','), c >= 6 ? e.err[c] * kRadToDeg : e.err[c]);
  for (int c = 0; c < kScoredComponents; ++c) {
    NumberOrNan(line.Char(','), c >= 6 ? e.sol_std[c] * kRadToDeg : e.sol_std[c]);
  }
  line.Char(',').Char(e.in_outage ? '1' : '0');
  for (int c = 0; c < 6 && reference_std_; ++c) NumberOrNan(line.Char(','), e.ref_std[c]);
  line.Char('\n').WriteTo(file_->stream());
  ++count_;
}

void ErrorsCsvWriter::Commit() {
  file_->Commit();
  committed_ = true;
}

void ErrorsCsvWriter::Revoke() {
  if (!committed_) return;
  std::remove(path_.c_str());
  if (created_dir_) ::rmdir(dir_.c_str());
  committed_ = false;
  created_dir_ = false;
}

void WriteJsonFile(const std::string& path, const std::function<void(JsonWriter&)>& body) {
  AtomicFile file(path);
  JsonWriter w(file.stream());
  body(w);
  file.stream() << '\n';
  file.Commit();
}

}  // namespace navtwin::gnss_ins
