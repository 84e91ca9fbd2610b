// The output files of a GNSS/INS run (docs/gnss-ins.md "Outputs"), written into one folder:
//   nav.nav         KF-GINS navigation format: week sow lat lon h vn ve vd roll pitch yaw
//                   (deg, m, m/s, deg)
//   nav.csv         t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg
//   std.csv         t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,
//                   vel_d_std_mps,att_n_std_deg,att_e_std_deg,att_d_std_deg,bg_x_std_deg_h,
//                   bg_y_std_deg_h,bg_z_std_deg_h,ba_x_std_mg,ba_y_std_mg,ba_z_std_mg
//                   [,sg_x_std_ppm,sg_y_std_ppm,sg_z_std_ppm,sa_x_std_ppm,sa_y_std_ppm,sa_z_std_ppm]
//                   (the error-state standard deviations of ins_state.h; att_* are the
//                   components of phi_n, about roll/pitch/yaw sigmas for a level attitude
//                   heading north; "nan" where the estimator computed none)
//   imu_errors.csv  t_s,bg_x_deg_h,bg_y_deg_h,bg_z_deg_h,ba_x_mg,ba_y_mg,ba_z_mg
//                   [,sg_x_ppm,sg_y_ppm,sg_z_ppm,sa_x_ppm,sa_y_ppm,sa_z_ppm]
// The bracketed scale-factor columns appear when the writer is built with scale_factors.
// With a reference (scoring.h), per scored method (filter, rts, batch) in the folder
// <method>/ (ErrorsCsvWriter), one row per compared reference epoch:
//   errors.csv      t_s,pos_n_err_m,pos_e_err_m,pos_d_err_m,vel_n_err_mps,vel_e_err_mps,
//                   vel_d_err_mps,roll_err_deg,pitch_err_deg,yaw_err_deg,pos_n_std_m,
//                   pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps,
//                   roll_std_deg,pitch_std_deg,yaw_std_deg,in_outage
//                   [,ref_pos_n_std_m,ref_pos_e_std_m,ref_pos_d_std_m,ref_vel_n_std_mps,
//                   ref_vel_e_std_mps,ref_vel_d_std_mps]
//                   (errors estimate minus reference; *_std the solution's sigmas of
//                   those errors, ScoredEpoch in scoring.h; in_outage 1 inside an injected
//                   outage, else 0; the bracketed reference sigmas for a GNSS reference;
//                   "nan" for components the reference lacks or sigmas not computed)
// Every file appears whole or not at all (core/io/atomic_file.h): nothing is left in the
// folder unless Commit() is called.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/io/kfgins.h"
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/gnss_ins/scoring.h"

namespace navtwin::gnss_ins {

class NavOutputWriter {
 public:
  /// `dir` must exist. Throws std::runtime_error when a file cannot be opened.
  NavOutputWriter(const std::string& dir, bool scale_factors);
  /// Appends one epoch (in time order) to the four files.
  void Write(const NavEpoch& epoch);
  /// Renames the four files into place.
  void Commit();
  std::size_t count() const { return count_; }

  /// The file names written into the folder.
  static const char* const kFiles[4];

 private:
  bool scale_factors_;
  std::size_t count_ = 0;
  KfginsNavWriter nav_;
  AtomicFile csv_;
  AtomicFile std_;
  AtomicFile errors_;
};

/// <out_dir>/<method>/errors.csv (layout above). The folder is created when missing and,
/// like the file, removed again unless Commit() succeeds (a failed run leaves nothing).
class ErrorsCsvWriter {
 public:
  /// reference_std: add the reference-sigma columns (a GNSS reference). Throws
  /// std::runtime_error when the folder or the file cannot be made.
  ErrorsCsvWriter(const std::string& out_dir, const std::string& method, bool reference_std);
  ~ErrorsCsvWriter();
  ErrorsCsvWriter(const ErrorsCsvWriter&) = delete;
  ErrorsCsvWriter& operator=(const ErrorsCsvWriter&) = delete;

  void Write(const ScoredEpoch& e);
  /// Renames the file into place.
  void Commit();
  /// Undoes a Commit (a later step of the run failed): removes the file, and the folder
  /// when this writer created it.
  void Revoke();
  std::size_t count() const { return count_; }
  const std::string& path() const { return path_; }

 private:
  std::string dir_;
  std::string path_;
  bool reference_std_;
  bool created_dir_ = false;
  bool committed_ = false;
  std::size_t count_ = 0;
  std::unique_ptr<AtomicFile> file_;
};

/// Writes `path` atomically with one JSON document produced by `body`.
void WriteJsonFile(const std::string& path, const std::function<void(JsonWriter&)>& body);

}  // namespace navtwin::gnss_ins
