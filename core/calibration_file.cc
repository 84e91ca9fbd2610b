// The calibration file (core/calibration_file.h, docs/calibration-file.md): reading with
// errors that name the file, line and key; atomic writing; compensation of IMU increments
// with the inverse model of core/imu_error_model.h; the compensating readers.
#include "core/calibration_file.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/LU>
#include <yaml-cpp/yaml.h>

#include "core/io/atomic_file.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/config/yaml_config.h"
#include "core/units.h"

namespace navtwin {
namespace {

using Triad = Eigen::Matrix<double, kTriadParameters, 1>;
using GSens = Eigen::Matrix<double, kGSensitivityParameters, 1>;

constexpr int kFileVersion = 1;
/// |det(K)| below this is taken as singular: K is I plus errors of a few percent, so a
/// determinant this small means a typo (e.g. a scale factor of -1), not a sensor.
constexpr double kMinDeterminant = 1e-6;

std::string Num(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

/// One number of a sequence element; `allow_null` (sigma only): null reads as NaN ("not
/// estimated"). Non-finite numbers are errors.
double Number(const ConfigNode& parent, const std::string& key, const YAML::Node& v, bool allow_null) {
  if (allow_null && v.IsNull()) return std::numeric_limits<double>::quiet_NaN();
  double x = 0.0;
  bool ok = v.IsScalar();
  if (ok) {
    try {
      x = v.as<double>();
    } catch (const YAML::Exception&) {
      ok = false;
    }
  }
  if (!ok) {
    throw InputError(parent.file(), v.Mark().line + 1, parent.path() + "." + key,
                     allow_null ? "expected numbers (or null)" : "expected numbers");
  }
  if (!std::isfinite(x)) {
    throw InputError(parent.file(), v.Mark().line + 1, parent.path() + "." + key, "must be finite, got " + Num(x));
  }
  return x;
}

Eigen::Vector3d ReadVector3(const ConfigNode& n, const std::string& key, bool allow_null) {
  const YAML::Node seq = n.yaml()[key];
  if (!seq.IsSequence() || seq.size() != 3) n.Fail(key, "expected [x, y, z] (3 numbers)");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = Number(n, key, seq[i], allow_null);
  return v;
}

Eigen::Matrix3d ReadMatrix3(const ConfigNode& n, const std::string& key, bool allow_null) {
  const YAML::Node rows = n.yaml()[key];
  if (!rows.IsSequence() || rows.size() != 3) n.Fail(key, "expected [[..], [..], [..]] (3 rows of 3 numbers)");
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    const YAML::Node row = rows[r];
    if (!row.IsSequence() || row.size() != 3) {
      throw InputError(n.file(), row.Mark().line + 1, n.path() + "." + key,
                       "row " + std::to_string(r + 1) + ": expected 3 numbers");
    }
    for (int c = 0; c < 3; ++c) m(r, c) = Number(n, key, row[c], allow_null);
  }
  return m;
}

/// A list of per-axis coefficient rows [[c1x, c1y, c1z], [c2x, ...], ...].
std::vector<Eigen::Vector3d> Rows(const ConfigNode& n, const std::string& key) {
  std::vector<Eigen::Vector3d> out;
  if (!n.Has(key)) return out;
  const YAML::Node rows = n.yaml()[key];
  if (!rows.IsSequence()) n.Fail(key, "expected a list of [x, y, z] rows (coefficients of dT, dT^2, ...)");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const YAML::Node row = rows[k];
    if (!row.IsSequence() || row.size() != 3) {
      throw InputError(n.file(), row.Mark().line + 1, n.path() + "." + key,
                       "row " + std::to_string(k + 1) + ": expected [x, y, z] (3 numbers)");
    }
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = Number(n, key, row[i], false);
    out.push_back(v);
  }
  return out;
}

/// scale_factor, misalignment_rad and the bias (key `bias_key`) of a triad block; sigma
/// blocks allow null entries and NaN for absent keys, value blocks 0.
Triad ParseTriad(const ConfigNode& n, const std::string& bias_key, bool sigma) {
  const double absent = sigma ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  Triad t = Triad::Constant(absent);
  if (n.Has("scale_factor")) t.head<3>() = ReadVector3(n, "scale_factor", sigma);
  if (n.Has("misalignment_rad")) {
    const Eigen::Matrix3d M = ReadMatrix3(n, "misalignment_rad", sigma);
    for (int r = 0; r < 3; ++r) {
      if (M(r, r) != 0.0 && !(sigma && std::isnan(M(r, r)))) {
        n.Fail("misalignment_rad", "diagonal entry (" + std::to_string(r + 1) + ", " + std::to_string(r + 1) +
                                       ") must be 0 (scale factors go in scale_factor), got " + Num(M(r, r)));
      }
      for (int c = 0; c < 3; ++c) {
        if (r != c) t[MisalignmentIndex(r, c)] = M(r, c);
      }
    }
  }
  if (n.Has(bias_key)) t.tail<3>() = ReadVector3(n, bias_key, sigma);
  return t;
}

void RequireInvertible(const ConfigNode& n, const Triad& t, const std::string& what) {
  const double det = TriadMatrix(t.data()).determinant();
  if (!(std::abs(det) >= kMinDeterminant)) {
    n.Fail("scale_factor", "I + diag(scale_factor) + misalignment_rad of the " + what +
                               " is not invertible (determinant " + Num(det) + ")");
  }
}

constexpr const char* kGSensKey = "g_sensitivity_rad_per_s_per_mps2";

ImuCalibration ParseImu(const ConfigNode& imu) {
  imu.RequireKeys({"gyro", "accel", "sigma", "temperature"});
  ImuCalibration c;
  const ConfigNode gyro = imu.Child("gyro"), accel = imu.Child("accel");
  gyro.RequireKeys({"scale_factor", "misalignment_rad", "bias_rad_per_s", kGSensKey});
  accel.RequireKeys({"scale_factor", "misalignment_rad", "bias_mps2"});
  c.gyro = ParseTriad(gyro, "bias_rad_per_s", false);
  c.accel = ParseTriad(accel, "bias_mps2", false);
  if (gyro.Has(kGSensKey)) {
    const Eigen::Matrix3d G = ReadMatrix3(gyro, kGSensKey, false);
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) c.g_sensitivity[3 * r + k] = G(r, k);
  }
  RequireInvertible(gyro, c.gyro, "gyro");
  RequireInvertible(accel, c.accel, "accelerometer");

  if (imu.Has("sigma")) {
    const ConfigNode sigma = imu.Child("sigma");
    sigma.RequireKeys({"gyro", "accel"});
    const ConfigNode sg = sigma.Child("gyro"), sa = sigma.Child("accel");
    sg.RequireKeys({"scale_factor", "misalignment_rad", "bias_rad_per_s", kGSensKey});
    sa.RequireKeys({"scale_factor", "misalignment_rad", "bias_mps2"});
    if (sigma.Has("gyro")) c.gyro_sigma = ParseTriad(sg, "bias_rad_per_s", true);
    if (sigma.Has("accel")) c.accel_sigma = ParseTriad(sa, "bias_mps2", true);
    if (sg.Has(kGSensKey)) {
      const Eigen::Matrix3d G = ReadMatrix3(sg, kGSensKey, true);
      GSens g;
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) g[3 * r + k] = G(r, k);
      c.g_sensitivity_sigma = g;
    }
  }

  if (imu.Has("temperature")) {
    const ConfigNode t = imu.Child("temperature");
    t.RequireKeys({"reference_degC", "gyro_bias_rad_per_s", "gyro_scale_factor", "accel_bias_mps2",
                   "accel_scale_factor"});
    TemperatureTerms terms;
    terms.reference_degC = t.Double("reference_degC", terms.reference_degC, -273.15, 1000.0);
    terms.gyro_bias_rad_per_s = Rows(t, "gyro_bias_rad_per_s");
    terms.gyro_scale_factor = Rows(t, "gyro_scale_factor");
    terms.accel_bias_mps2 = Rows(t, "accel_bias_mps2");
    terms.accel_scale_factor = Rows(t, "accel_scale_factor");
    c.temperature = terms;
  }
  return c;
}

MagCorrection ParseMag(const ConfigNode& mag) {
  // `soft_iron` is the name files written before the iron model (core/mag_iron_model.h) gave
  // the correction A; it is read as A, never as the soft iron S.
  mag.RequireKeys({"hard_iron_uT", "correction", "soft_iron", "field_uT"});
  if (mag.Has("correction") && mag.Has("soft_iron")) {
    mag.Fail("soft_iron", "give the correction once (correction, or soft_iron in older files)");
  }
  MagCorrection m;
  if (mag.Has("hard_iron_uT")) m.hard_iron_uT = ReadVector3(mag, "hard_iron_uT", false);
  const char* key = mag.Has("correction") ? "correction" : "soft_iron";
  if (mag.Has(key)) {
    m.correction = ReadMatrix3(mag, key, false);
    const double det = m.correction.determinant();
    if (!(std::abs(det) >= kMinDeterminant)) {
      mag.Fail(key, "not invertible (determinant " + Num(det) + ")");
    }
  }
  m.field_uT = mag.NonNegative("field_uT", 0.0);
  return m;
}

/// A sigma vector of the installation: each entry > 0 and finite, or null (not estimated).
Eigen::Vector3d PositiveOrNullVector(const ConfigNode& n, const std::string& key) {
  const Eigen::Vector3d v = ReadVector3(n, key, true);
  for (int i = 0; i < 3; ++i) {
    if (!std::isnan(v[i]) && !(v[i] > 0.0)) n.Fail(key, "a sigma must be > 0 (or null: not estimated), got " + Num(v[i]));
  }
  return v;
}

ImuInstallation ParseImuInstallation(const ConfigNode& n) {
  n.RequireKeys({"imu_mounting_rpy_rad", "imu_time_offset_s", "sigma"});
  for (const char* key : {"imu_mounting_rpy_rad", "imu_time_offset_s"}) {
    if (!n.Has(key)) {
      n.Fail(key, "required in an installation section (write 0 for a value that is zero; a missing one is "
                  "never taken as 0)");
    }
  }
  ImuInstallation x;
  x.mounting_rpy_rad = ReadVector3(n, "imu_mounting_rpy_rad", false);
  const double limits[3] = {kPi, kPi / 2.0, kPi};  // ZYX Euler ranges of roll, pitch, yaw
  const char* names[3] = {"roll", "pitch", "yaw"};
  for (int i = 0; i < 3; ++i) {
    if (std::abs(x.mounting_rpy_rad[i]) > limits[i] + 1e-12) {
      n.Fail("imu_mounting_rpy_rad", std::string(names[i]) + " " + Num(x.mounting_rpy_rad[i]) + " rad is beyond +-" +
                                         Num(limits[i]) + " (ZYX Euler angles in radians; degrees given?)");
    }
  }
  x.time_offset_s = Number(n, "imu_time_offset_s", n.yaml()["imu_time_offset_s"], false);
  if (n.Has("sigma")) {
    const ConfigNode sigma = n.Child("sigma");
    sigma.RequireKeys({"imu_mounting_rpy_rad", "imu_time_offset_s"});
    if (sigma.Has("imu_mounting_rpy_rad")) x.mounting_sigma_rad = PositiveOrNullVector(sigma, "imu_mounting_rpy_rad");
    if (sigma.Has("imu_time_offset_s")) {
      const double s = Number(sigma, "imu_time_offset_s", sigma.yaml()["imu_time_offset_s"], true);
      if (!std::isnan(s) && !(s > 0.0)) {
        sigma.Fail("imu_time_offset_s", "a sigma must be > 0 (or null: not estimated), got " + Num(s));
      }
      x.time_offset_sigma_s = s;
    }
  }
  return x;
}

// ---------------------------------------------------------------- writing

/// A number of the file in the shortest form that reads back exactly; in sigma blocks
/// (`sigma`) NaN, a value not estimated, is written null. Other non-finite values cannot be
/// written (std::invalid_argument; the atomic file then leaves nothing behind).
std::string Value(double x, bool sigma = false) {
  if (sigma && std::isnan(x)) return "null";
  if (!std::isfinite(x)) {
    throw std::invalid_argument("calibration file: cannot write the non-finite value " + Num(x));
  }
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

std::string Vec(const Eigen::Vector3d& v, bool sigma = false) {
  return "[" + Value(v[0], sigma) + ", " + Value(v[1], sigma) + ", " + Value(v[2], sigma) + "]";
}

std::string Mat(const Eigen::Matrix3d& m, bool sigma = false) {
  return "[" + Vec(m.row(0).transpose(), sigma) + ", " + Vec(m.row(1).transpose(), sigma) + ", " +
         Vec(m.row(2).transpose(), sigma) + "]";
}

/// The misalignment matrix of a triad block (diagonal 0).
Eigen::Matrix3d Misalignment(const Triad& t) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c) M(r, c) = t[MisalignmentIndex(r, c)];
  return M;
}

Eigen::Matrix3d GMatrix(const GSens& g) { return GSensitivityMatrix(g.data()); }

void WriteTriad(std::ostream& out, const std::string& indent, const Triad& t, const std::string& bias_key,
                bool sigma) {
  out << indent << "scale_factor: " << Vec(t.head<3>(), sigma) << "\n"
      << indent << "misalignment_rad: " << Mat(Misalignment(t), sigma) << "\n"
      << indent << bias_key << ": " << Vec(t.tail<3>(), sigma) << "\n";
}

void WriteRows(std::ostream& out, const std::string& key, const std::vector<Eigen::Vector3d>& rows) {
  if (rows.empty()) return;
  out << "    " << key << ": [";
  for (std::size_t k = 0; k < rows.size(); ++k) out << (k ? ", " : "") << Vec(rows[k]);
  out << "]\n";
}

void WriteImuInstallation(std::ostream& s, const ImuInstallation& x) {
  s << "installation:\n  imu_mounting_rpy_rad: " << Vec(x.mounting_rpy_rad) << "\n  imu_time_offset_s: "
    << Value(x.time_offset_s) << "\n";
  if (!x.mounting_sigma_rad && !x.time_offset_sigma_s) return;
  s << "  sigma:\n";
  if (x.mounting_sigma_rad) s << "    imu_mounting_rpy_rad: " << Vec(*x.mounting_sigma_rad, true) << "\n";
  if (x.time_offset_sigma_s) s << "    imu_time_offset_s: " << Value(*x.time_offset_sigma_s, true) << "\n";
}

/// The compensation of one sample with a calibration whose temperature terms are already
/// evaluated; the triad blocks' biases are scaled by dt so that the inverse model of
/// core/imu_error_model.h (linear in f_m and b) works on increments.
ImuSample Compensate(const ImuCalibration& c, const ImuSample& s) {
  Triad accel = c.accel, gyro = c.gyro;
  accel.tail<3>() *= s.dt_s;
  gyro.tail<3>() *= s.dt_s;
  ImuSample out = s;
  out.dv_b_mps = CorrectedSpecificForce(accel.data(), s.dv_b_mps);
  out.dtheta_b_rad = CorrectedRate(gyro.data(), c.g_sensitivity.data(), s.dtheta_b_rad, out.dv_b_mps);
  return out;
}

class CalibratedImu : public ImuReader {
 public:
  CalibratedImu(std::unique_ptr<ImuReader> inner, ImuCalibration c) : inner_(std::move(inner)), c_(std::move(c)) {}
  bool Next(ImuSample* sample) override {
    if (!inner_->Next(sample)) return false;
    *sample = Compensate(c_, *sample);
    return true;
  }
  const std::string& path() const override { return inner_->path(); }

 private:
  std::unique_ptr<ImuReader> inner_;
  ImuCalibration c_;
};

class CalibratedMag : public MagReader {
 public:
  CalibratedMag(std::unique_ptr<MagReader> inner, const MagCorrection& c) : inner_(std::move(inner)), c_(c) {}
  bool Next(MagSample* sample) override {
    if (!inner_->Next(sample)) return false;
    *sample = ApplyMagCorrection(c_, *sample);
    return true;
  }
  const std::string& path() const override { return inner_->path(); }

 private:
  std::unique_ptr<MagReader> inner_;
  MagCorrection c_;
};

}  // namespace

ImuCalibration ImuCalibration::At(double temperature_degC) const {
  ImuCalibration out = *this;
  out.temperature.reset();
  if (!temperature) return out;
  if (!std::isfinite(temperature_degC)) {
    throw std::invalid_argument("ImuCalibration::At: the temperature must be finite, got " + Num(temperature_degC));
  }
  const double dT = temperature_degC - temperature->reference_degC;
  const auto add = [dT](const std::vector<Eigen::Vector3d>& coefficients, double* xyz) {
    double power = 1.0;
    for (const Eigen::Vector3d& c : coefficients) {
      power *= dT;
      for (int i = 0; i < 3; ++i) xyz[i] += c[i] * power;
    }
  };
  add(temperature->gyro_scale_factor, out.gyro.data());
  add(temperature->gyro_bias_rad_per_s, out.gyro.data() + 9);
  add(temperature->accel_scale_factor, out.accel.data());
  add(temperature->accel_bias_mps2, out.accel.data() + 9);
  return out;
}

CalibrationFile ReadCalibrationFile(const std::string& path) {
  const ConfigNode root = LoadYamlFile(path);
  root.RequireKeys({"navtwin_calibration", "created_by", "imu", "mag", "installation"});
  if (!root.Has("navtwin_calibration")) {
    root.Fail("navtwin_calibration", "required: the file's format version (" + std::to_string(kFileVersion) +
                                         "); is this a navtwin calibration file?");
  }
  const int version = root.Int("navtwin_calibration", kFileVersion, 1, 1000000);
  if (version != kFileVersion) {
    root.Fail("navtwin_calibration", "version " + std::to_string(version) + " is not known (this navtwin reads " +
                                         std::to_string(kFileVersion) + ")");
  }
  CalibrationFile f;
  f.created_by = root.String("created_by", "");
  if (root.Has("imu")) f.imu = ParseImu(root.Child("imu"));
  if (root.Has("mag")) f.mag = ParseMag(root.Child("mag"));
  if (root.Has("installation")) f.installation = ParseImuInstallation(root.Child("installation"));
  return f;
}

void WriteCalibrationFile(const std::string& path, const CalibrationFile& file) {
  AtomicFile out(path);
  std::ostream& s = out.stream();
  YAML::Emitter created_by;
  created_by << YAML::DoubleQuoted << file.created_by;
  s << "# navtwin calibration file (docs/calibration-file.md); SI units as named in the keys\n"
    << "navtwin_calibration: " << kFileVersion << "\n"
    << "created_by: " << created_by.c_str() << "\n";
  if (file.imu) {
    const ImuCalibration& c = *file.imu;
    s << "imu:\n  gyro:\n";
    WriteTriad(s, "    ", c.gyro, "bias_rad_per_s", false);
    s << "    " << kGSensKey << ": " << Mat(GMatrix(c.g_sensitivity)) << "\n  accel:\n";
    WriteTriad(s, "    ", c.accel, "bias_mps2", false);
    if (c.gyro_sigma || c.accel_sigma || c.g_sensitivity_sigma) {
      s << "  sigma:\n";
      if (c.gyro_sigma || c.g_sensitivity_sigma) {
        s << "    gyro:\n";
        if (c.gyro_sigma) WriteTriad(s, "      ", *c.gyro_sigma, "bias_rad_per_s", true);
        if (c.g_sensitivity_sigma) s << "      " << kGSensKey << ": " << Mat(GMatrix(*c.g_sensitivity_sigma), true) << "\n";
      }
      if (c.accel_sigma) {
        s << "    accel:\n";
        WriteTriad(s, "      ", *c.accel_sigma, "bias_mps2", true);
      }
    }
    if (c.temperature) {
      const TemperatureTerms& t = *c.temperature;
      s << "  temperature:\n    reference_degC: " << Value(t.reference_degC) << "\n";
      WriteRows(s, "gyro_bias_rad_per_s", t.gyro_bias_rad_per_s);
      WriteRows(s, "gyro_scale_factor", t.gyro_scale_factor);
      WriteRows(s, "accel_bias_mps2", t.accel_bias_mps2);
      WriteRows(s, "accel_scale_factor", t.accel_scale_factor);
    }
  }
  if (file.mag) {
    s << "mag:\n  hard_iron_uT: " << Vec(file.mag->hard_iron_uT) << "\n  correction: " << Mat(file.mag->correction)
      << "\n  field_uT: " << Value(file.mag->field_uT) << "\n";
  }
  if (file.installation) WriteImuInstallation(s, *file.installation);
  out.Commit();
}

ImuSample ApplyImuCalibration(const ImuCalibration& c, const ImuSample& s) {
  // At the reference temperature the temperature terms add nothing: the constant blocks.
  return Compensate(c, s);
}

MagSample ApplyMagCorrection(const MagCorrection& c, const MagSample& s) {
  MagSample out = s;
  out.m_b_uT = RemoveIron(s.m_b_uT, c.hard_iron_uT, c.correction);
  return out;
}

std::unique_ptr<ImuReader> CalibratedImuReader(std::unique_ptr<ImuReader> inner, const ImuCalibration& c,
                                               double temperature_degC) {
  const double t_degC = std::isnan(temperature_degC) && c.temperature ? c.temperature->reference_degC : temperature_degC;
  ImuCalibration at = c.At(t_degC);
  for (const auto& [triad, name] : {std::pair<const Triad*, const char*>{&at.gyro, "gyro"}, {&at.accel, "accelerometer"}}) {
    const double det = TriadMatrix(triad->data()).determinant();
    if (!(std::abs(det) >= kMinDeterminant)) {
      throw std::invalid_argument(std::string("the ") + name + " calibration at " + Num(t_degC) +
                                  " degC has a singular I + diag(s) + M (determinant " + Num(det) + ")");
    }
  }
  return std::make_unique<CalibratedImu>(std::move(inner), std::move(at));
}

std::unique_ptr<MagReader> CalibratedMagReader(std::unique_ptr<MagReader> inner, const MagCorrection& c) {
  return std::make_unique<CalibratedMag>(std::move(inner), c);
}

std::unique_ptr<ImuReader> OpenImu(const std::string& path, const std::string& calibration_path,
                                   double temperature_degC) {
  if (calibration_path.empty()) return OpenImu(path);
  const CalibrationFile file = ReadCalibrationFile(calibration_path);
  if (!file.imu) throw InputError(calibration_path, 0, "imu", "no imu section: the file does not calibrate an IMU");
  if (file.installation) {
    throw InputError(calibration_path, 0, "installation",
                     "an installation section (IMU mounting and time offset) is applied by navigate and smooth "
                     "only; this command has neither: use a file without it");
  }
  return CalibratedImuReader(OpenImu(path), *file.imu, temperature_degC);
}

std::unique_ptr<MagReader> OpenMag(const std::string& path, const std::string& calibration_path) {
  if (calibration_path.empty()) return OpenMag(path);
  const CalibrationFile file = ReadCalibrationFile(calibration_path);
  if (!file.mag) {
    throw InputError(calibration_path, 0, "mag", "no mag section: the file does not calibrate a magnetometer");
  }
  return CalibratedMagReader(OpenMag(path), *file.mag);
}

}  // namespace navtwin
