#include "problems/gnss_ins/output.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "core/io/text_line.h"
#include "core/io/write_queue.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::gnss_ins {

/// What a row of the output files needs from an epoch, copied when the epoch is handed to
/// the writer thread (core/io/write_queue.h). std_size: entries of NavEpoch::std (0 when
/// the estimator computed none).
struct OutputRow {
  NavState nav;
  ImuErrors imu;
  double std[err::kSize21];
  int std_size;
  bool with_std;
};

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

void WriteNavCsvHeader(std::ostream& out) {
  out << "t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg\n";
}

void WriteStdCsvHeader(std::ostream& out, bool scale_factors) {
  out << "t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,"
         "vel_d_std_mps,att_n_std_deg,att_e_std_deg,att_d_std_deg,bg_x_std_deg_h,"
         "bg_y_std_deg_h,bg_z_std_deg_h,ba_x_std_mg,ba_y_std_mg,ba_z_std_mg";
  if (scale_factors) out << ",sg_x_std_ppm,sg_y_std_ppm,sg_z_std_ppm,sa_x_std_ppm,sa_y_std_ppm,sa_z_std_ppm";
  out << '\n';
}

/// nav.csv's row: the navigation record's fields (kfgins.h AppendNavFields) comma separated.
void WriteNavCsvRow(std::ostream& out, const NavState& s) {
  TextLine line;
  AppendNavFields(s, ',', &line);
  line.Char('\n').WriteTo(out);
}

OutputRow MakeOutputRow(const NavEpoch& epoch, bool with_std) {
  RequireWritableNavState(epoch.state.nav);  // refused now, not later on the writer thread
  OutputRow row{epoch.state.nav, epoch.state.imu, {}, 0, with_std};
  if (!with_std) return row;
  row.std_size = static_cast<int>(std::min<Eigen::Index>(epoch.std.size(), err::kSize21));
  for (int i = 0; i < row.std_size; ++i) row.std[i] = epoch.std[i];
  return row;
}

/// Standard deviations in the units of the header; NaN where not computed.
void WriteStdCsvRow(std::ostream& out, const OutputRow& row, bool scale_factors) {
  const int n = scale_factors ? err::kSize21 : err::kSize15;
  double sd[err::kSize21];
  for (int i = 0; i < n; ++i) {
    double scale = 1.0;
    if (i >= err::kAtt && i < err::kBg) scale = kRadToDeg;
    if (i >= err::kBg && i < err::kBa) scale = 1.0 / kDegPerHour_radps;
    if (i >= err::kBa && i < err::kSg) scale = 1.0 / kMilliG_mps2;
    if (i >= err::kSg) scale = 1.0 / kPpm;
    sd[i] = i < row.std_size ? row.std[i] * scale : std::numeric_limits<double>::quiet_NaN();
  }
  Row(out, row.nav.t_s, sd, n);
}

/// imu_errors.csv's row in the units of its header.
void WriteImuErrorsRow(std::ostream& out, const OutputRow& row, bool scale_factors) {
  const ImuErrors& e = row.imu;
  double imu[12];
  for (int i = 0; i < 3; ++i) {
    imu[i] = e.bg_radps[i] / kDegPerHour_radps;
    imu[3 + i] = e.ba_mps2[i] / kMilliG_mps2;
    imu[6 + i] = e.sg[i] / kPpm;
    imu[9 + i] = e.sa[i] / kPpm;
  }
  Row(out, row.nav.t_s, imu, scale_factors ? 12 : 6);
}

/// `to` as a hard link of `from` (replacing a file of that name), or a copy where the file
/// system cannot link. Throws std::runtime_error when neither works.
void LinkOrCopy(const std::string& from, const std::string& to) {
  std::error_code ec;
  std::filesystem::remove(to, ec);
  std::filesystem::create_hard_link(from, to, ec);
  if (!ec) return;
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
  if (ec) throw std::runtime_error("cannot link or copy " + from + " to " + to + ": " + ec.message());
}

/// A folder for a method's files: created when missing (returns whether it was).
bool MakeMethodFolder(const std::string& dir) {
  struct stat st;
  if (::stat(dir.c_str(), &st) != 0) {
    if (::mkdir(dir.c_str(), 0755) != 0) throw std::runtime_error("cannot create the folder " + dir);
    return true;
  }
  if (!S_ISDIR(st.st_mode)) throw std::runtime_error(dir + " exists and is not a folder");
  return false;
}

void WriteGnssCsvRow(std::ostream& out, const GnssSample& g, bool in_outage) {
  TextLine line;
  line.Number(g.t_s).Char(',').Number(g.lat_rad * kRadToDeg).Char(',').Number(g.lon_rad * kRadToDeg);
  line.Char(',').Number(g.h_m);
  for (int i = 0; i < 3; ++i) NumberOrNan(line.Char(','), g.pos_std_ned_m[i]);
  line.Char(',').Char(in_outage ? '1' : '0').Char('\n').WriteTo(out);
}

}  // namespace

const char* const NavOutputWriter::kFiles[4] = {"nav.nav", "nav.csv", "std.csv", "imu_errors.csv"};

NavOutputWriter::NavOutputWriter(const std::string& dir, bool scale_factors)
    : scale_factors_(scale_factors),
      nav_(dir + "/" + kFiles[0]),
      csv_(dir + "/" + kFiles[1]),
      std_(dir + "/" + kFiles[2]),
      errors_(dir + "/" + kFiles[3]),
      rows_(std::make_unique<Rows>(this)) {
  WriteNavCsvHeader(csv_.stream());
  WriteStdCsvHeader(std_.stream(), scale_factors_);
  errors_.stream() << "t_s,bg_x_deg_h,bg_y_deg_h,bg_z_deg_h,ba_x_mg,ba_y_mg,ba_z_mg";
  if (scale_factors_) errors_.stream() << ",sg_x_ppm,sg_y_ppm,sg_z_ppm,sa_x_ppm,sa_y_ppm,sa_z_ppm";
  errors_.stream() << '\n';
}

/// The rows on their way to the four files, formatted on the queue's writer thread.
struct NavOutputWriter::Rows {
  explicit Rows(NavOutputWriter* w)
      : queue([w](const std::vector<OutputRow>& rows) { Write(*w, rows); }) {}
  static void Write(NavOutputWriter& w, const std::vector<OutputRow>& rows) {
    for (const OutputRow& row : rows) {
      TextLine fields;  // nav.csv's row, and nav.nav's record after the week: formatted once
      AppendNavFields(row.nav, ',', &fields);
      w.nav_.WriteFields(row.nav.gps_week, fields.view());
      fields.Char('\n').WriteTo(w.csv_.stream());
      if (!row.with_std) continue;
      WriteStdCsvRow(w.std_.stream(), row, w.scale_factors_);
      WriteImuErrorsRow(w.errors_.stream(), row, w.scale_factors_);
    }
  }
  WriteQueue<OutputRow> queue;
};

NavOutputWriter::~NavOutputWriter() { rows_.reset(); }  // the writer thread ends before the files go

void NavOutputWriter::Write(const NavEpoch& epoch, bool with_std) {
  rows_->queue.Push(MakeOutputRow(epoch, with_std));
  ++count_;
}

void NavOutputWriter::Commit() {
  rows_->queue.Finish();
  nav_.Commit();
  csv_.Commit();
  std_.Commit();
  errors_.Commit();
}

void NavOutputWriter::Revoke() {
  nav_.Revoke();
  csv_.Revoke();
  std_.Revoke();
  errors_.Revoke();
}

MethodOutputWriter::MethodOutputWriter(const std::string& out_dir, const std::string& method, bool scale_factors)
    : dir_(out_dir + "/" + method), scale_factors_(scale_factors) {
  created_dir_ = MakeMethodFolder(dir_);
  try {
    nav_csv_ = std::make_unique<AtomicFile>(dir_ + "/nav.csv");
    std_csv_ = std::make_unique<AtomicFile>(dir_ + "/std.csv");
  } catch (...) {
    nav_csv_.reset();
    if (created_dir_) ::rmdir(dir_.c_str());
    throw;
  }
  WriteNavCsvHeader(nav_csv_->stream());
  WriteStdCsvHeader(std_csv_->stream(), scale_factors_);
  rows_ = std::make_unique<Rows>(this);
}

MethodOutputWriter::~MethodOutputWriter() {
  rows_.reset();  // the writer thread ends before the files go
  nav_csv_.reset();  // each removes its temporary unless committed
  std_csv_.reset();
  errors_csv_.reset();
  residuals_csv_.reset();
  if (created_dir_ && !committed_) ::rmdir(dir_.c_str());
}

std::vector<AtomicFile*> MethodOutputWriter::Files() const {
  std::vector<AtomicFile*> files;
  for (const auto* f : {&nav_csv_, &std_csv_, &errors_csv_, &residuals_csv_}) {
    if (*f) files.push_back(f->get());
  }
  return files;
}

/// The rows on their way to nav.csv and std.csv, formatted on the queue's writer thread.
struct MethodOutputWriter::Rows {
  explicit Rows(MethodOutputWriter* w)
      : queue([w](const std::vector<OutputRow>& rows) { Write(*w, rows); }) {}
  static void Write(MethodOutputWriter& w, const std::vector<OutputRow>& rows) {
    for (const OutputRow& row : rows) {
      WriteNavCsvRow(w.nav_csv_->stream(), row.nav);
      if (row.with_std) WriteStdCsvRow(w.std_csv_->stream(), row, w.scale_factors_);
    }
  }
  WriteQueue<OutputRow> queue;
};

void MethodOutputWriter::Write(const NavEpoch& epoch, bool with_std) {
  if (shares_top_level_) throw std::logic_error("MethodOutputWriter: Write on a method sharing the top-level files");
  rows_->queue.Push(MakeOutputRow(epoch, with_std));
  ++count_;
}

void MethodOutputWriter::ShareTopLevelFiles() {
  shares_top_level_ = true;
  rows_.reset();
  nav_csv_.reset();  // removes the temporaries
  std_csv_.reset();
}

void MethodOutputWriter::OpenErrors(bool reference_std) {
  reference_std_ = reference_std;
  errors_csv_ = std::make_unique<AtomicFile>(errors_path());
  std::ostream& out = errors_csv_->stream();
  out << "t_s,pos_n_err_m,pos_e_err_m,pos_d_err_m,vel_n_err_mps,vel_e_err_mps,vel_d_err_mps,roll_err_deg,"
         "pitch_err_deg,yaw_err_deg,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,"
         "vel_d_std_mps,roll_std_deg,pitch_std_deg,yaw_std_deg,in_outage";
  if (reference_std_) {
    out << ",ref_pos_n_std_m,ref_pos_e_std_m,ref_pos_d_std_m,ref_vel_n_std_mps,ref_vel_e_std_mps,ref_vel_d_std_mps";
  }
  out << '\n';
}

void MethodOutputWriter::WriteErrors(const ScoredEpoch& e) {
  TextLine line;
  line.Number(e.t_s);
  for (int c = 0; c < kScoredComponents; ++c) NumberOrNan(line.Char(','), c >= 6 ? e.err[c] * kRadToDeg : e.err[c]);
  for (int c = 0; c < kScoredComponents; ++c) {
    NumberOrNan(line.Char(','), c >= 6 ? e.sol_std[c] * kRadToDeg : e.sol_std[c]);
  }
  line.Char(',').Char(e.in_outage ? '1' : '0');
  for (int c = 0; c < 6 && reference_std_; ++c) NumberOrNan(line.Char(','), e.ref_std[c]);
  line.Char('\n').WriteTo(errors_csv_->stream());
}

void MethodOutputWriter::WriteResiduals(const std::vector<MeasurementResidual>& rows) {
  if (residuals_csv_) throw std::logic_error("MethodOutputWriter: residuals.csv written twice");
  residuals_csv_ = std::make_unique<AtomicFile>(dir_ + "/residuals.csv");
  std::ostream& out = residuals_csv_->stream();
  out << "t_s,sensor,dof,chi2,rejected\n";
  for (const MeasurementResidual& r : rows) {
    TextLine line;
    NumberOrNan(line, r.t_s);
    line.Char(',');
    for (const char c : r.sensor) line.Char(c);
    line.Char(',').Integer(r.dof).Char(',');
    NumberOrNan(line, r.chi2);
    line.Char(',').Char(r.rejected ? '1' : '0').Char('\n').WriteTo(out);
  }
}

void MethodOutputWriter::Commit() {
  if (rows_) rows_->queue.Finish();
  for (AtomicFile* f : Files()) f->Commit();
  committed_ = true;
  if (!shares_top_level_) return;
  const std::string top = dir_.substr(0, dir_.find_last_of('/'));
  for (const char* name : {"nav.csv", "std.csv"}) LinkOrCopy(top + "/" + name, dir_ + "/" + name);
}

void MethodOutputWriter::Revoke() {
  for (AtomicFile* f : Files()) f->Revoke();
  if (shares_top_level_ && committed_) {
    for (const char* name : {"/nav.csv", "/std.csv"}) std::remove((dir_ + name).c_str());
  }
  committed_ = false;
  // Empty unless a file's temporary is still there; the destructor tries again after them.
  if (created_dir_) ::rmdir(dir_.c_str());
}

void WriteGnssCsv(std::ostream& out, const std::vector<GnssSample>& used, const std::vector<GnssSample>& removed) {
  out << "t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage\n";
  std::size_t u = 0, r = 0;
  while (u < used.size() || r < removed.size()) {
    const bool take_removed = u == used.size() || (r < removed.size() && removed[r].t_s < used[u].t_s);
    WriteGnssCsvRow(out, take_removed ? removed[r++] : used[u++], take_removed);
  }
}

void WriteJsonFile(const std::string& path, const std::function<void(JsonWriter&)>& body) {
  AtomicFile file(path);
  JsonWriter w(file.stream());
  body(w);
  file.stream() << '\n';
  file.Commit();
}

}  // namespace navtwin::gnss_ins
