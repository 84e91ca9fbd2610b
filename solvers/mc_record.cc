#include "solvers/mc_record.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace navtwin::mc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::uint32_t kRecordMagic = 0x4e544d43;  // "NTMC"

class ByteWriter {
 public:
  template <typename T>
  void Put(const T& x) {
    bytes_.append(reinterpret_cast<const char*>(&x), sizeof x);
  }
  void PutString(const std::string& s) {
    Put<std::uint64_t>(s.size());
    bytes_ += s;
  }
  void PutDoubles(const std::vector<double>& v) {
    Put<std::uint64_t>(v.size());
    bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
  }
  std::string Take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
  template <typename T>
  T Get() {
    T x;
    Need(sizeof x);
    std::memcpy(&x, bytes_.data() + at_, sizeof x);
    at_ += sizeof x;
    return x;
  }
  std::string GetString() {
    const std::size_t n = Count(1);
    std::string s = bytes_.substr(at_, n);
    at_ += n;
    return s;
  }
  std::vector<double> GetDoubles() {
    const std::size_t n = Count(sizeof(double));
    std::vector<double> v(n);
    if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(double));
    at_ += n * sizeof(double);
    return v;
  }
  std::size_t Count(std::size_t item_bytes) {
    const std::uint64_t n = Get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / item_bytes) Fail();
    return static_cast<std::size_t>(n);
  }
  bool AtEnd() const { return at_ == bytes_.size(); }

 private:
  void Need(std::size_t n) const {
    if (n > bytes_.size() - at_) Fail();
  }
  [[noreturn]] static void Fail() { throw std::runtime_error("Monte Carlo run record: truncated or corrupt bytes"); }
  const std::string& bytes_;
  std::size_t at_ = 0;
};

void PutQuantity(ByteWriter& w, const Quantity& q) {
  w.PutString(q.name);
  w.PutString(q.unit);
  w.Put(q.scale);
  w.PutString(q.axis_name);
  w.Put<std::uint64_t>(q.components.size());
  for (const std::string& c : q.components) w.PutString(c);
  w.PutDoubles(q.axis);
  w.PutDoubles(q.error);
  w.PutDoubles(q.covariance);
}

Quantity GetQuantity(ByteReader& r) {
  Quantity q;
  q.name = r.GetString();
  q.unit = r.GetString();
  q.scale = r.Get<double>();
  q.axis_name = r.GetString();
  const std::size_t n = r.Count(sizeof(std::uint64_t));
  for (std::size_t i = 0; i < n; ++i) q.components.push_back(r.GetString());
  q.axis = r.GetDoubles();
  q.error = r.GetDoubles();
  q.covariance = r.GetDoubles();
  const std::size_t d = q.components.size();
  if (q.error.size() != q.axis.size() * d || q.covariance.size() != q.axis.size() * d * d) {
    throw std::runtime_error("Monte Carlo run record: quantity " + q.name + " has inconsistent sizes");
  }
  return q;
}

}  // namespace

Quantity Quantity::Empty(std::string name, std::string unit, double scale, std::string axis_name,
                         std::vector<std::string> components, std::vector<double> axis) {
  Quantity q;
  q.name = std::move(name);
  q.unit = std::move(unit);
  q.scale = scale;
  q.axis_name = std::move(axis_name);
  q.components = std::move(components);
  q.axis = std::move(axis);
  const std::size_t d = q.components.size();
  q.error.assign(q.axis.size() * d, kNaN);
  q.covariance.assign(q.axis.size() * d * d, kNaN);
  return q;
}

void Quantity::Set(int point, const double* error_si, const double* covariance_si) {
  const int d = dim();
  for (int i = 0; i < d; ++i) error[point * d + i] = error_si[i];
  for (int i = 0; i < d * d; ++i) covariance[point * d * d + i] = covariance_si[i];
}

void Quantity::SetDiagonal(int point, const double* error_si, const double* sigma_si) {
  const int d = dim();
  std::vector<double> cov(d * d, 0.0);
  for (int i = 0; i < d; ++i) cov[i * d + i] = sigma_si[i] * sigma_si[i];
  Set(point, error_si, cov.data());
}

std::vector<double> WholeSecondGrid(double t0_s, double t_end_s) {
  std::vector<double> grid;
  const int n = static_cast<int>(std::floor(t_end_s - t0_s + 1e-6));
  for (int k = 1; k <= n; ++k) grid.push_back(t0_s + k);
  if (grid.empty()) grid.push_back(t_end_s);
  return grid;
}

std::string SerializeRunRecord(const RunRecord& record) {
  ByteWriter w;
  w.Put(kRecordMagic);
  w.Put<std::int64_t>(record.run);
  w.Put(record.seed);
  w.Put<std::uint64_t>(record.methods.size());
  for (const MethodRecord& m : record.methods) {
    w.PutString(m.method);
    w.PutString(m.failure);
    w.Put(m.run_time_s);
    w.Put<std::uint64_t>(m.quantities.size());
    for (const Quantity& q : m.quantities) PutQuantity(w, q);
  }
  return w.Take();
}

RunRecord DeserializeRunRecord(const std::string& bytes) {
  ByteReader r(bytes);
  if (r.Get<std::uint32_t>() != kRecordMagic) throw std::runtime_error("Monte Carlo run record: not a record");
  RunRecord record;
  record.run = static_cast<int>(r.Get<std::int64_t>());
  record.seed = r.Get<std::uint64_t>();
  const std::size_t methods = r.Count(1);
  for (std::size_t i = 0; i < methods; ++i) {
    MethodRecord m;
    m.method = r.GetString();
    m.failure = r.GetString();
    m.run_time_s = r.Get<double>();
    const std::size_t quantities = r.Count(1);
    for (std::size_t k = 0; k < quantities; ++k) m.quantities.push_back(GetQuantity(r));
    record.methods.push_back(std::move(m));
  }
  if (!r.AtEnd()) throw std::runtime_error("Monte Carlo run record: trailing bytes");
  return record;
}

}  // namespace navtwin::mc
