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
//                   (std.csv and imu_errors.csv at the output epochs the writer's caller
//                   marks, by default one per second: GnssInsConfig::std_rate_hz)
// The bracketed scale-factor columns appear when the writer is built with scale_factors.
// Per method the run computed (filter, rts, batch, filter_adapted, rts_adapted), in the
// folder <method>/ (MethodOutputWriter):
//   nav.csv, std.csv  the columns above, at the same output epochs (for the output method
//                     hard links to the top-level files)
//   residuals.csv     t_s,sensor,dof,chi2,rejected: one row per measurement of an estimator
//                     with residuals of its own (filter, batch; MeasurementResidual in
//                     solution.h); chi2 and dof "nan" / 0 for a sample counted without an
//                     update
// and with a reference (scoring.h), one row per compared reference epoch:
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
// The GNSS fixes the run read (WriteGnssCsv), antenna positions as given:
//   gnss.csv        t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage
// The whole folder is described in docs/run-folder.md.
// Every file appears whole or not at all (core/io/atomic_file.h): nothing is left in the
// folder unless Commit() is called.
#pragma once

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/io/kfgins.h"
#include "core/types.h"
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/gnss_ins/scoring.h"
#include "problems/gnss_ins/solution.h"

namespace navtwin::gnss_ins {

class NavOutputWriter {
 public:
  /// `dir` must exist. Throws std::runtime_error when a file cannot be opened.
  NavOutputWriter(const std::string& dir, bool scale_factors);
  ~NavOutputWriter();
  NavOutputWriter(const NavOutputWriter&) = delete;
  NavOutputWriter& operator=(const NavOutputWriter&) = delete;
  /// Appends one epoch (in time order) to nav.nav and nav.csv and, with `with_std`, to
  /// std.csv and imu_errors.csv. The state is checked here (std::invalid_argument for one
  /// AppendNavFields refuses); the rows are formatted and written on a writer thread
  /// (core/io/write_queue.h), so the caller does not wait for the disk.
  void Write(const NavEpoch& epoch, bool with_std);
  /// Waits for the rows written, then renames the four files into place.
  void Commit();
  /// Undoes a Commit (a later step of the run failed): removes the four files.
  void Revoke();
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
  struct Rows;
  std::unique_ptr<Rows> rows_;  ///< the writer thread's queue; last, so it ends first
};

/// The folder <out_dir>/<method>/ (layout above). The folder is created when missing and,
/// like its files, removed again unless Commit() succeeds (a failed run leaves nothing).
class MethodOutputWriter {
 public:
  /// Opens nav.csv and std.csv (with the scale-factor columns when scale_factors). Throws
  /// std::runtime_error when the folder or a file cannot be made.
  MethodOutputWriter(const std::string& out_dir, const std::string& method, bool scale_factors);
  ~MethodOutputWriter();
  MethodOutputWriter(const MethodOutputWriter&) = delete;
  MethodOutputWriter& operator=(const MethodOutputWriter&) = delete;

  /// Appends one output epoch (in time order) to nav.csv and, with `with_std`, std.csv;
  /// checked and handed to a writer thread as NavOutputWriter::Write does.
  void Write(const NavEpoch& epoch, bool with_std);
  /// The method is the run's output method: its nav.csv and std.csv are the top level's
  /// (<out_dir>/nav.csv, std.csv), which Commit() hard-links (copies where the file system
  /// cannot link) instead of writing them twice; Write() is not called then. Commit the top
  /// level's files first.
  void ShareTopLevelFiles();
  /// Opens errors.csv; reference_std: with the reference-sigma columns (a GNSS reference).
  void OpenErrors(bool reference_std);
  /// Appends a compared epoch to errors.csv (OpenErrors first).
  void WriteErrors(const ScoredEpoch& e);
  /// Writes residuals.csv with `rows` (whole; at most once).
  void WriteResiduals(const std::vector<MeasurementResidual>& rows);
  /// Renames the files into place.
  void Commit();
  /// Undoes a Commit (a later step of the run failed): removes the files, and the folder
  /// when this writer created it.
  void Revoke();
  std::size_t count() const { return count_; }
  /// <out_dir>/<method>/errors.csv
  std::string errors_path() const { return dir_ + "/errors.csv"; }

 private:
  std::string dir_;
  bool scale_factors_;
  bool reference_std_ = false;
  bool created_dir_ = false;
  bool committed_ = false;
  bool shares_top_level_ = false;
  std::size_t count_ = 0;
  std::unique_ptr<AtomicFile> nav_csv_, std_csv_;
  std::unique_ptr<AtomicFile> errors_csv_, residuals_csv_;  ///< null until opened
  struct Rows;
  std::unique_ptr<Rows> rows_;  ///< nav.csv's and std.csv's writer thread (null when shared)
  /// The files opened, in the order above.
  std::vector<AtomicFile*> Files() const;
};

/// gnss.csv (layout above) into `out`: the fixes the estimators used and those the injected
/// outages removed (in_outage 1), merged in time order; sigmas "nan" where the file has none.
void WriteGnssCsv(std::ostream& out, const std::vector<GnssSample>& used, const std::vector<GnssSample>& removed);

/// Writes `path` atomically with one JSON document produced by `body`.
void WriteJsonFile(const std::string& path, const std::function<void(JsonWriter&)>& body);

}  // namespace navtwin::gnss_ins
