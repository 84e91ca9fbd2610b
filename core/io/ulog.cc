#include "core/io/ulog.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "core/io/input_error.h"
#include "core/io/ulog_format.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin {
namespace {

using ulog::BaseType;

constexpr double kMinFixType = 3;  // PX4 fix_type: 0-1 none, 2 2D, 3 3D, 4+ DGPS/RTK
// PX4's marker for "no sample" in *_timestamp_relative fields (INT32_MAX).
constexpr double kRelativeTimestampInvalid = 2147483647.0;
// Flag bits ('B'): incompat_flags[0] bit 0 = data appended; other bits are unknown to us.
constexpr std::uint8_t kIncompatDataAppended = 0x01;
constexpr std::size_t kFlagBitsSize = 40;  // compat[8], incompat[8], appended_offsets[3]
constexpr long long kFlagBitsOffset = 16;  // directly after the file header

std::string CString(const std::uint8_t* p, std::size_t n) {
  std::size_t len = 0;
  while (len < n && p[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(p), len);
}

std::string FormatNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

bool SubscriptionHasField(const ULogSubscription& sub, const std::string& field) {
  for (const ULogField& f : sub.fields) {
    if (f.name == field) return true;
  }
  return false;
}

}  // namespace

std::string ULogField::Describe() const {
  std::string text = name + ":" + type;
  if (array_length > 0) text += "[" + std::to_string(array_length) + "]";
  return text;
}

std::string ULogSubscription::Label() const {
  return multi_id == 0 ? topic : topic + "[" + std::to_string(multi_id) + "]";
}

// ---------------------------------------------------------------------------------------
class ULogFile::Impl {
 public:
  explicit Impl(const std::string& path) : stream_(path) {}

  bool Next(const std::string* topic, int multi_id);
  const ulog::Leaf& FindLeaf(const std::string& field) const;
  const std::uint8_t* data() const { return message_.payload.data() + 2; }
  InputError Error(const std::string& field, const std::string& reason) const {
    return InputError::AtByte(stream_.path(), message_.byte_offset, field, reason);
  }

  // One subscription's byte layout, parallel to subscriptions_.
  struct Layout {
    ulog::Layout layout;
    std::unordered_map<std::string, std::size_t> leaf_index;
    std::size_t timestamp_offset = 0;
  };

  ulog::MessageStream stream_;
  ulog::Message message_;
  std::map<std::string, ulog::Format> formats_;
  std::vector<ULogSubscription> subscriptions_;
  std::vector<Layout> layouts_;
  std::unordered_map<int, std::size_t> active_;  // msg_id -> index in subscriptions_
  std::size_t current_ = 0;
  bool has_current_ = false;
  std::map<std::string, std::string> info_;
  std::map<std::string, double> parameters_;
  std::vector<ULogLoggedString> logged_;
  std::size_t dropouts_ = 0;
  double dropout_total_s_ = 0.0;
  std::vector<long long> appended_offsets_;
  std::size_t unknown_messages_ = 0;

 private:
  bool Handle();  // true for a data message, which becomes the current one
  void RequireSize(std::size_t min_size, const char* what) const;
  ulog::TypedName ParseKey(std::size_t key_len_at, std::size_t* value_at) const;
  std::string ValueText(const ulog::TypedName& key, std::size_t value_at) const;
  void HandleFlagBits();
  void HandleFormat();
  void HandleInfo();
  void HandleParameter();
  void HandleSubscription();
  void HandleRemove();
  void HandleData();
  void HandleLogged(bool tagged);
  void HandleDropout();
};

void ULogFile::Impl::RequireSize(std::size_t min_size, const char* what) const {
  if (message_.payload.size() < min_size) {
    throw Error("msg_size", std::string(what) + " message ('" + message_.type + "') has " +
                                std::to_string(message_.payload.size()) +
                                " bytes, needs at least " + std::to_string(min_size));
  }
}

bool ULogFile::Impl::Next(const std::string* topic, int multi_id) {
  while (stream_.Next(&message_)) {
    if (!Handle()) continue;
    const ULogSubscription& sub = subscriptions_[current_];
    if (topic == nullptr || (sub.topic == *topic && sub.multi_id == multi_id)) return true;
  }
  has_current_ = false;
  return false;
}

bool ULogFile::Impl::Handle() {
  switch (message_.type) {
    case 'B': HandleFlagBits(); return false;
    case 'F': HandleFormat(); return false;
    case 'I': HandleInfo(); return false;
    case 'M': ParseKey(1, nullptr); return false;  // multi-info: checked, not kept
    case 'P': HandleParameter(); return false;
    case 'Q': ParseKey(1, nullptr); return false;  // default parameters: checked, not kept
    case 'A': HandleSubscription(); return false;
    case 'R': HandleRemove(); return false;
    case 'D': HandleData(); return true;
    case 'L': HandleLogged(false); return false;
    case 'C': HandleLogged(true); return false;
    case 'O': HandleDropout(); return false;
    case 'S': return false;  // sync marker: only for resynchronising corrupt streams
    default: ++unknown_messages_; return false;  // the spec asks readers to skip these
  }
}

void ULogFile::Impl::HandleFlagBits() {
  if (message_.byte_offset != kFlagBitsOffset) {
    throw Error("msg_type", "flag bits message ('B') must directly follow the header");
  }
  RequireSize(kFlagBitsSize, "flag bits");
  const std::uint8_t* incompat = message_.payload.data() + 8;
  for (int i = 0; i < 8; ++i) {
    const std::uint8_t unknown = i == 0 ? incompat[0] & ~kIncompatDataAppended : incompat[i];
    if (unknown != 0) {
      throw Error("incompat_flags", "unknown incompatible flag bits set (byte " +
                                        std::to_string(i) + " = " + std::to_string(incompat[i]) +
                                        "): this log needs a newer reader");
    }
  }
  if ((incompat[0] & kIncompatDataAppended) == 0) return;
  long long previous = stream_.position();
  for (int i = 0; i < 3; ++i) {
    const long long offset =
        static_cast<long long>(ulog::DecodeUnsigned(message_.payload.data() + 16 + 8 * i, 8));
    if (offset == 0) continue;
    if (offset < previous) {
      throw Error("appended_offsets", "offset " + std::to_string(offset) +
                                          " is not after the definitions and earlier offsets");
    }
    appended_offsets_.push_back(offset);
    previous = offset;
  }
  stream_.SetAppendedOffsets(appended_offsets_);
}

void ULogFile::Impl::HandleFormat() {
  RequireSize(1, "format");
  const std::string text(message_.payload.begin(), message_.payload.end());
  ulog::Format format = ulog::ParseFormat(text, stream_.path(), message_.byte_offset);
  const std::string name = format.name;
  if (!formats_.emplace(name, std::move(format)).second) {
    throw Error(name, "format '" + name + "' is defined twice");
  }
}

// Key of an 'I', 'M', 'P' or 'Q' message: uint8 key_len at key_len_at, then the key.
ulog::TypedName ULogFile::Impl::ParseKey(std::size_t key_len_at, std::size_t* value_at) const {
  RequireSize(key_len_at + 1, "key-value");
  const std::size_t key_len = message_.payload[key_len_at];
  const std::size_t key_at = key_len_at + 1;
  if (key_at + key_len > message_.payload.size()) {
    throw Error("key_len", "key of " + std::to_string(key_len) + " bytes runs past the message");
  }
  const std::string text(message_.payload.begin() + static_cast<std::ptrdiff_t>(key_at),
                         message_.payload.begin() + static_cast<std::ptrdiff_t>(key_at + key_len));
  ulog::TypedName key;
  std::string reason;
  if (!ulog::ParseTypedName(text, &key, &reason, true)) throw Error("key", reason);
  if (value_at != nullptr) *value_at = key_at + key_len;
  return key;
}

// The value of a key-value message as text: char[n] as a string, numbers in decimal.
std::string ULogFile::Impl::ValueText(const ulog::TypedName& key, std::size_t value_at) const {
  BaseType type;
  if (!ulog::ParseBaseType(key.type, &type)) {
    throw Error(key.name, "type '" + key.type + "' is not a basic type");
  }
  const std::size_t count = key.array_length > 0 ? static_cast<std::size_t>(key.array_length) : 1;
  const std::size_t value_size = message_.payload.size() - value_at;
  const std::uint8_t* value = message_.payload.data() + value_at;
  if (type == BaseType::kChar) return CString(value, value_size);
  if (value_size != count * ulog::BaseTypeSize(type)) {
    throw Error(key.name, "value has " + std::to_string(value_size) + " bytes, type '" + key.type +
                              "' needs " + std::to_string(count * ulog::BaseTypeSize(type)));
  }
  std::string text;
  for (std::size_t i = 0; i < count; ++i) {
    if (i > 0) text += ",";
    text += FormatNumber(ulog::DecodeAsDouble(type, value + i * ulog::BaseTypeSize(type)));
  }
  return text;
}

void ULogFile::Impl::HandleInfo() {
  std::size_t value_at = 0;
  const ulog::TypedName key = ParseKey(0, &value_at);
  info_[key.name] = ValueText(key, value_at);
}

void ULogFile::Impl::HandleParameter() {
  std::size_t value_at = 0;
  const ulog::TypedName key = ParseKey(0, &value_at);
  if ((key.type != "int32_t" && key.type != "float") || key.array_length != 0) {
    throw Error(key.name, "parameter type must be int32_t or float, got '" + key.type + "'");
  }
  if (message_.payload.size() - value_at != 4) {
    throw Error(key.name, "value has " + std::to_string(message_.payload.size() - value_at) +
                              " bytes, needs 4");
  }
  const BaseType type = key.type == "float" ? BaseType::kFloat : BaseType::kInt32;
  parameters_[key.name] = ulog::DecodeAsDouble(type, message_.payload.data() + value_at);
}

void ULogFile::Impl::HandleSubscription() {
  RequireSize(4, "subscription");
  ULogSubscription sub;
  sub.multi_id = message_.payload[0];
  sub.msg_id = static_cast<int>(ulog::DecodeUnsigned(message_.payload.data() + 1, 2));
  sub.topic.assign(message_.payload.begin() + 3, message_.payload.end());
  if (formats_.count(sub.topic) == 0) {
    throw Error("message_name",
                "subscription to unknown format '" + sub.topic + "' (no 'F' message defines it)");
  }
  if (active_.count(sub.msg_id) != 0) {
    throw Error("msg_id", "msg_id " + std::to_string(sub.msg_id) + " is already subscribed");
  }
  Layout layout;
  layout.layout = ulog::Flatten(sub.topic, formats_, stream_.path());
  for (std::size_t i = 0; i < layout.layout.leaves.size(); ++i) {
    const ulog::Leaf& leaf = layout.layout.leaves[i];
    layout.leaf_index[leaf.name] = i;
    sub.fields.push_back({leaf.name, ulog::BaseTypeName(leaf.type), leaf.array_length});
  }
  const auto ts = layout.leaf_index.find("timestamp");
  if (ts == layout.leaf_index.end() || layout.layout.leaves[ts->second].type != BaseType::kUInt64 ||
      layout.layout.leaves[ts->second].array_length != 0) {
    throw Error(sub.topic + ".timestamp", "a subscribed format needs a uint64_t timestamp field");
  }
  layout.timestamp_offset = layout.layout.leaves[ts->second].offset;
  active_[sub.msg_id] = subscriptions_.size();
  subscriptions_.push_back(std::move(sub));
  layouts_.push_back(std::move(layout));
}

void ULogFile::Impl::HandleRemove() {
  RequireSize(2, "unsubscription");
  active_.erase(static_cast<int>(ulog::DecodeUnsigned(message_.payload.data(), 2)));
}

void ULogFile::Impl::HandleData() {
  RequireSize(2, "data");
  const int msg_id = static_cast<int>(ulog::DecodeUnsigned(message_.payload.data(), 2));
  const auto it = active_.find(msg_id);
  if (it == active_.end()) {
    throw Error("msg_id", "data for msg_id " + std::to_string(msg_id) +
                              ", which no subscription ('A') defines");
  }
  const ulog::Layout& layout = layouts_[it->second].layout;
  const std::size_t size = message_.payload.size() - 2;
  if (size < layout.min_size || size > layout.size) {
    throw Error(subscriptions_[it->second].Label(),
                "data has " + std::to_string(size) + " bytes, format '" +
                    subscriptions_[it->second].topic + "' has " + std::to_string(layout.size) +
                    " (" + std::to_string(layout.min_size) + " without trailing padding)");
  }
  current_ = it->second;
  has_current_ = true;
}

void ULogFile::Impl::HandleLogged(bool tagged) {
  const std::size_t text_at = tagged ? 11 : 9;  // level, [tag,] timestamp
  RequireSize(text_at, "logged string");
  const std::uint8_t* p = message_.payload.data();
  ULogLoggedString entry;
  // PX4 writes the level as an ASCII digit ('0' emergency .. '7' debug).
  entry.level = p[0] >= '0' && p[0] <= '7' ? p[0] - '0' : p[0];
  if (tagged) entry.tag = static_cast<int>(ulog::DecodeUnsigned(p + 1, 2));
  entry.timestamp_us = ulog::DecodeUnsigned(p + text_at - 8, 8);
  entry.text = CString(p + text_at, message_.payload.size() - text_at);
  logged_.push_back(std::move(entry));
}

void ULogFile::Impl::HandleDropout() {
  RequireSize(2, "dropout");
  ++dropouts_;
  dropout_total_s_ += 1e-3 * static_cast<double>(ulog::DecodeUnsigned(message_.payload.data(), 2));
}

const ulog::Leaf& ULogFile::Impl::FindLeaf(const std::string& field) const {
  const Layout& layout = layouts_[current_];
  const auto it = layout.leaf_index.find(field);
  if (it == layout.leaf_index.end()) {
    throw Error(subscriptions_[current_].topic + "." + field,
                "no such field in format '" + subscriptions_[current_].topic + "'");
  }
  return layout.layout.leaves[it->second];
}

// ---------------------------------------------------------------------------------------
ULogFile::ULogFile(const std::string& path) : impl_(std::make_unique<Impl>(path)) {}
ULogFile::~ULogFile() = default;
ULogFile::ULogFile(ULogFile&&) noexcept = default;
ULogFile& ULogFile::operator=(ULogFile&&) noexcept = default;

bool ULogFile::Next() { return impl_->Next(nullptr, 0); }

bool ULogFile::NextOf(const std::string& topic, int multi_id) {
  return impl_->Next(&topic, multi_id);
}

const ULogSubscription& ULogFile::subscription() const {
  if (!impl_->has_current_) throw std::logic_error("ULogFile: no current data message");
  return impl_->subscriptions_[impl_->current_];
}

long long ULogFile::byte_offset() const { return impl_->message_.byte_offset; }

std::uint64_t ULogFile::timestamp_us() const {
  subscription();  // checks that there is a current message
  return ulog::DecodeUnsigned(impl_->data() + impl_->layouts_[impl_->current_].timestamp_offset, 8);
}

bool ULogFile::HasField(const std::string& field) const {
  subscription();
  return impl_->layouts_[impl_->current_].leaf_index.count(field) != 0;
}

std::string ULogFile::FieldType(const std::string& field) const {
  subscription();
  return ulog::BaseTypeName(impl_->FindLeaf(field).type);
}

double ULogFile::GetDouble(const std::string& field) const {
  subscription();
  const ulog::Leaf& leaf = impl_->FindLeaf(field);
  if (leaf.array_length != 0) {
    throw impl_->Error(subscription().topic + "." + field,
                       "is an array of " + std::to_string(leaf.array_length) + " (use GetArray)");
  }
  return ulog::DecodeAsDouble(leaf.type, impl_->data() + leaf.offset);
}

double ULogFile::GetArray(const std::string& field, int index) const {
  subscription();
  const ulog::Leaf& leaf = impl_->FindLeaf(field);
  if (index < 0 || index >= leaf.array_length) {
    throw impl_->Error(subscription().topic + "." + field, "index " + std::to_string(index) +
                                                               " outside an array of " +
                                                               std::to_string(leaf.array_length));
  }
  return ulog::DecodeAsDouble(leaf.type,
                              impl_->data() + leaf.offset +
                                  static_cast<std::size_t>(index) * ulog::BaseTypeSize(leaf.type));
}

std::string ULogFile::GetString(const std::string& field) const {
  subscription();
  const ulog::Leaf& leaf = impl_->FindLeaf(field);
  if (leaf.type != BaseType::kChar) {
    throw impl_->Error(subscription().topic + "." + field, "is not a char array");
  }
  return CString(impl_->data() + leaf.offset,
                 static_cast<std::size_t>(std::max(1, leaf.array_length)));
}

const std::string& ULogFile::path() const { return impl_->stream_.path(); }
int ULogFile::version() const { return impl_->stream_.version(); }
const std::map<std::string, std::string>& ULogFile::info() const { return impl_->info_; }
const std::map<std::string, double>& ULogFile::parameters() const { return impl_->parameters_; }
const std::vector<ULogSubscription>& ULogFile::subscriptions() const {
  return impl_->subscriptions_;
}
const std::vector<ULogLoggedString>& ULogFile::logged_strings() const { return impl_->logged_; }
std::size_t ULogFile::dropout_count() const { return impl_->dropouts_; }
double ULogFile::dropout_total_s() const { return impl_->dropout_total_s_; }
long long ULogFile::truncated_at_byte() const { return impl_->stream_.truncated_at_byte(); }
const std::vector<long long>& ULogFile::appended_offsets() const {
  return impl_->appended_offsets_;
}
std::size_t ULogFile::unknown_message_count() const { return impl_->unknown_messages_; }

std::vector<ULogSubscription> ListULogSubscriptions(const std::string& path) {
  ULogFile log(path);
  while (log.Next()) {
  }
  return log.subscriptions();
}

// ---------------------------------------------------------------------------------------
// Typed readers.
namespace {

// A topic a typed reader can take its samples from, in order of preference.
struct Candidate {
  const char* topic;
  const char* needed_field;         // the candidate counts only if it has this field
  const char* relative_time_field;  // "" or a *_timestamp_relative field (old sensor_combined)
};

// The subscription (instance 0) that matches a candidate, or nullptr.
const ULogSubscription* FindSubscription(const std::vector<ULogSubscription>& subs,
                                         const Candidate& candidate) {
  for (const ULogSubscription& sub : subs) {
    if (sub.topic == candidate.topic && sub.multi_id == 0 &&
        SubscriptionHasField(sub, candidate.needed_field)) {
      return &sub;
    }
  }
  return nullptr;
}

// The first candidate subscribed in the file; InputError if none is.
Candidate ChooseTopic(const std::string& path, const std::vector<Candidate>& candidates,
                      const std::string& what) {
  const std::vector<ULogSubscription> subs = ListULogSubscriptions(path);
  std::string names;
  for (const Candidate& c : candidates) {
    if (FindSubscription(subs, c) != nullptr) return c;
    names += (names.empty() ? "" : " or ") + std::string(c.topic) + "." + c.needed_field;
  }
  throw InputError(path, 0, what, "no " + names + " in this log");
}

// One topic instance in time order. Repeated times are skipped (real logs repeat a
// sample now and then); a time that goes backwards is an InputError at its byte offset.
class TimeOrderedTopic {
 public:
  TimeOrderedTopic(const std::string& path, const Candidate& source)
      : log_(path), topic_(source.topic), relative_field_(source.relative_time_field) {}

  bool Next() {
    while (log_.NextOf(topic_)) {
      std::int64_t t_us = static_cast<std::int64_t>(log_.timestamp_us());
      if (!relative_field_.empty()) {
        const double relative_us = log_.GetDouble(relative_field_);
        if (relative_us == kRelativeTimestampInvalid) continue;  // no new sample of this sensor
        t_us += static_cast<std::int64_t>(relative_us);
      }
      if (has_time_ && t_us == time_us_) continue;
      if (has_time_ && t_us < time_us_) {
        throw InputError::AtByte(
            log_.path(), log_.byte_offset(),
            topic_ + "." + (relative_field_.empty() ? "timestamp" : relative_field_),
            "time goes backwards: " + std::to_string(t_us) + " us after " +
                std::to_string(time_us_) + " us");
      }
      has_previous_ = has_time_;
      previous_us_ = time_us_;
      time_us_ = t_us;
      has_time_ = true;
      return true;
    }
    return false;
  }

  const ULogFile& log() const { return log_; }
  const std::string& topic() const { return topic_; }
  double t_s() const { return static_cast<double>(time_us_) * kMicrosecond_s; }
  bool has_previous() const { return has_previous_; }
  double dt_s() const { return static_cast<double>(time_us_ - previous_us_) * kMicrosecond_s; }

  /// A finite field value; InputError naming the field otherwise.
  double Finite(const std::string& field, int index = -1) const {
    const double v = index < 0 ? log_.GetDouble(field) : log_.GetArray(field, index);
    if (!std::isfinite(v)) {
      throw InputError::AtByte(log_.path(), log_.byte_offset(), topic_ + "." + field, "not finite");
    }
    return v;
  }
  /// As Finite(), NaN when the format has no such field.
  double FiniteOrNaN(const std::string& field) const {
    return log_.HasField(field) ? Finite(field) : std::numeric_limits<double>::quiet_NaN();
  }
  Eigen::Vector3d Vector(const std::string& field) const {
    return {Finite(field, 0), Finite(field, 1), Finite(field, 2)};
  }
  /// A standard deviation, which must be positive and finite.
  double Sigma(const std::string& field) const {
    const double v = Finite(field);
    if (v <= 0.0) {
      throw InputError::AtByte(log_.path(), log_.byte_offset(), topic_ + "." + field,
                               "standard deviation must be positive, got " + FormatNumber(v));
    }
    return v;
  }

 private:
  ULogFile log_;
  std::string topic_;
  std::string relative_field_;
  bool has_time_ = false;
  bool has_previous_ = false;
  std::int64_t time_us_ = 0;
  std::int64_t previous_us_ = 0;
};

class ULogImuReader final : public ImuReader {
 public:
  explicit ULogImuReader(const std::string& path)
      : path_(path),
        topic_(path, ChooseTopic(path, {{"sensor_combined", "gyro_rad", ""}}, "imu")) {}

  bool Next(ImuSample* sample) override {
    while (topic_.Next()) {
      const double gyro_dt_s = IntegralSeconds("gyro_integral_dt");
      const double accel_dt_s = IntegralSeconds("accelerometer_integral_dt");
      double dt_s = gyro_dt_s;
      if (topic_.has_previous()) {
        dt_s = topic_.dt_s();
      } else if (gyro_dt_s <= 0.0) {
        continue;  // no interval for the first sample: it only starts the clock
      }
      sample->t_s = topic_.t_s();
      sample->dt_s = dt_s;
      // The rates are averages over the integration time; without one, over dt_s.
      sample->dtheta_b_rad = topic_.Vector("gyro_rad") * (gyro_dt_s > 0.0 ? gyro_dt_s : dt_s);
      sample->dv_b_mps =
          topic_.Vector("accelerometer_m_s2") * (accel_dt_s > 0.0 ? accel_dt_s : dt_s);
      return true;
    }
    return false;
  }
  const std::string& path() const override { return path_; }

 private:
  // Integration time in seconds: integers are microseconds, floats seconds (old PX4);
  // 0 when the field is absent.
  double IntegralSeconds(const std::string& field) const {
    if (!topic_.log().HasField(field)) return 0.0;
    const double v = topic_.Finite(field);
    if (v < 0.0) {
      throw InputError::AtByte(path_, topic_.log().byte_offset(), "sensor_combined." + field,
                               "negative integration time");
    }
    const std::string type = topic_.log().FieldType(field);
    return type == "float" || type == "double" ? v : v * kMicrosecond_s;
  }

  std::string path_;
  TimeOrderedTopic topic_;
};

// Position field names and scales of a GNSS topic: new float names (deg, m) or old
// integer names (1e-7 deg, mm). Height: the ellipsoid field when logged, else MSL.
struct GnssFields {
  std::string lat, lon, height;
  double deg_per_unit = 1.0;
  double m_per_unit = 1.0;
  bool ellipsoid = true;
};

GnssFields GnssFieldsOf(const ULogSubscription& sub) {
  const bool new_names = SubscriptionHasField(sub, "latitude_deg");
  GnssFields f;
  f.lat = new_names ? "latitude_deg" : "lat";
  f.lon = new_names ? "longitude_deg" : "lon";
  f.deg_per_unit = new_names ? 1.0 : 1e-7;
  f.m_per_unit = new_names ? 1.0 : 1e-3;
  const std::string ellipsoid = new_names ? "altitude_ellipsoid_m" : "alt_ellipsoid";
  f.ellipsoid = SubscriptionHasField(sub, ellipsoid);
  f.height = f.ellipsoid ? ellipsoid : (new_names ? "altitude_msl_m" : "alt");
  return f;
}

std::vector<Candidate> GnssCandidates() {
  return {{"vehicle_gps_position", "fix_type", ""}, {"sensor_gps", "fix_type", ""}};
}

class ULogGnssReader final : public GnssReader {
 public:
  explicit ULogGnssReader(const std::string& path)
      : path_(path), topic_(path, ChooseTopic(path, GnssCandidates(), "gnss")) {}

  bool Next(GnssSample* s) override {
    while (topic_.Next()) {
      const double fix_type = topic_.Finite("fix_type");
      if (fix_type < kMinFixType) continue;  // no 3D fix: position not usable
      const GnssFields f = GnssFieldsOf(topic_.log().subscription());
      const double lat_deg = topic_.Finite(f.lat) * f.deg_per_unit;
      const double lon_deg = topic_.Finite(f.lon) * f.deg_per_unit;
      if (std::abs(lat_deg) > 90.0 || std::abs(lon_deg) > 180.0) {
        throw InputError::AtByte(path_, topic_.log().byte_offset(), topic_.topic() + "." + f.lat,
                                 "latitude/longitude out of range");
      }
      s->t_s = topic_.t_s();
      s->lat_rad = lat_deg * kDegToRad;
      s->lon_rad = lon_deg * kDegToRad;
      s->h_m = topic_.Finite(f.height) * f.m_per_unit;
      const double eph = topic_.Sigma("eph");
      s->pos_std_ned_m = {eph, eph, topic_.Sigma("epv")};
      s->has_velocity =
          !topic_.log().HasField("vel_ned_valid") || topic_.Finite("vel_ned_valid") != 0.0;
      if (s->has_velocity) {
        s->v_n_mps = {topic_.Finite("vel_n_m_s"), topic_.Finite("vel_e_m_s"),
                      topic_.Finite("vel_d_m_s")};
        s->vel_std_ned_mps = Eigen::Vector3d::Constant(topic_.Sigma("s_variance_m_s"));
      } else {
        s->v_n_mps.setZero();
        s->vel_std_ned_mps.setConstant(std::numeric_limits<double>::quiet_NaN());
      }
      s->quality = static_cast<int>(fix_type);
      s->num_sats = topic_.log().HasField("satellites_used")
                        ? static_cast<int>(topic_.Finite("satellites_used"))
                        : 0;
      return true;
    }
    return false;
  }
  const std::string& path() const override { return path_; }

 private:
  std::string path_;
  TimeOrderedTopic topic_;
};

class ULogMagReader final : public MagReader {
 public:
  explicit ULogMagReader(const std::string& path)
      : path_(path),
        source_(
            ChooseTopic(path,
                        {{"vehicle_magnetometer", "magnetometer_ga", ""},
                         {"sensor_mag", "x", ""},
                         {"sensor_combined", "magnetometer_ga", "magnetometer_timestamp_relative"}},
                        "magnetometer")),
        topic_(path, source_) {}

  bool Next(MagSample* s) override {
    if (!topic_.Next()) return false;
    const bool xyz = std::string(source_.topic) == "sensor_mag";
    const Eigen::Vector3d gauss =
        xyz ? Eigen::Vector3d(topic_.Finite("x"), topic_.Finite("y"), topic_.Finite("z"))
            : topic_.Vector("magnetometer_ga");
    s->t_s = topic_.t_s();
    s->m_b_uT = kGauss_uT * gauss;
    return true;
  }
  const std::string& path() const override { return path_; }

 private:
  std::string path_;
  Candidate source_;
  TimeOrderedTopic topic_;
};

class ULogBaroReader final : public BaroReader {
 public:
  explicit ULogBaroReader(const std::string& path)
      : path_(path),
        topic_(path, ChooseTopic(path,
                                 {{"vehicle_air_data", "baro_alt_meter", ""},
                                  {"sensor_combined", "baro_alt_meter", "baro_timestamp_relative"}},
                                 "barometer")) {}

  bool Next(BaroSample* s) override {
    if (!topic_.Next()) return false;
    const ULogFile& log = topic_.log();
    s->t_s = topic_.t_s();
    s->altitude_m = topic_.Finite("baro_alt_meter");
    s->pressure_pa = topic_.FiniteOrNaN("baro_pressure_pa");
    s->temperature_degC = log.HasField("baro_temp_celcius")
                              ? topic_.Finite("baro_temp_celcius")
                              : topic_.FiniteOrNaN("ambient_temperature");
    return true;
  }
  const std::string& path() const override { return path_; }

 private:
  std::string path_;
  TimeOrderedTopic topic_;
};

// Per-stream time statistics for DescribeULog.
struct StreamTimes {
  TimeTagStats stats;
  std::uint64_t last_us = 0;
  std::size_t repeated = 0;
  std::size_t backwards = 0;
};

void AddTimeNotes(const std::string& label, const StreamTimes& times,
                  std::vector<std::string>* notes) {
  if (times.repeated > 0) {
    notes->push_back(label + ": " + std::to_string(times.repeated) +
                     " repeated timestamps (typed readers skip them)");
  }
  if (times.backwards > 0) {
    notes->push_back(label + ": " + std::to_string(times.backwards) +
                     " timestamps going backwards (typed readers stop with an error)");
  }
}

void AddGnssNote(const std::vector<ULogSubscription>& subs, std::vector<std::string>* notes) {
  for (const Candidate& c : GnssCandidates()) {
    const ULogSubscription* sub = FindSubscription(subs, c);
    if (sub == nullptr) continue;
    const GnssFields f = GnssFieldsOf(*sub);
    notes->push_back("GNSS from " + sub->topic + ": height from " + f.height +
                     (f.ellipsoid ? " (WGS84 ellipsoid)" : " (MSL: no ellipsoid height logged)"));
    return;
  }
}

}  // namespace

std::unique_ptr<ImuReader> OpenULogImu(const std::string& path) {
  return std::make_unique<ULogImuReader>(path);
}

std::unique_ptr<GnssReader> OpenULogGnss(const std::string& path) {
  return std::make_unique<ULogGnssReader>(path);
}

std::unique_ptr<MagReader> OpenULogMag(const std::string& path) {
  return std::make_unique<ULogMagReader>(path);
}

std::unique_ptr<BaroReader> OpenULogBaro(const std::string& path) {
  return std::make_unique<ULogBaroReader>(path);
}

FileSummary DescribeULog(const std::string& path) {
  ULogFile log(path);
  std::unordered_map<int, StreamTimes> times;  // by msg_id
  while (log.Next()) {
    StreamTimes& st = times[log.subscription().msg_id];
    const std::uint64_t t_us = log.timestamp_us();
    if (st.stats.count() > 0 && t_us == st.last_us) ++st.repeated;
    if (st.stats.count() > 0 && t_us < st.last_us) ++st.backwards;
    st.stats.Add(static_cast<double>(t_us) * kMicrosecond_s);
    st.last_us = t_us;
  }
  FileSummary summary;
  summary.path = path;
  summary.kind = "ulog";
  summary.notes.push_back("ULog version " + std::to_string(log.version()));
  for (const char* key : {"sys_name", "ver_hw"}) {
    const auto it = log.info().find(key);
    if (it != log.info().end()) summary.notes.push_back(std::string(key) + ": " + it->second);
  }
  for (const ULogSubscription& sub : log.subscriptions()) {
    std::vector<std::string> fields;
    for (const ULogField& f : sub.fields) fields.push_back(f.Describe());
    const StreamTimes& st = times[sub.msg_id];
    summary.streams.push_back(StreamSummary::FromStats(sub.Label(), st.stats, std::move(fields)));
    AddTimeNotes(sub.Label(), st, &summary.notes);
  }
  summary.notes.push_back("dropouts: " + std::to_string(log.dropout_count()) + ", total " +
                          FormatNumber(log.dropout_total_s() * 1e3) + " ms");
  summary.notes.push_back("logged messages: " + std::to_string(log.logged_strings().size()));
  AddGnssNote(log.subscriptions(), &summary.notes);
  for (long long offset : log.appended_offsets()) {
    summary.notes.push_back("appended data from byte " + std::to_string(offset));
  }
  if (log.unknown_message_count() > 0) {
    summary.notes.push_back("skipped messages of unknown type: " +
                            std::to_string(log.unknown_message_count()));
  }
  if (log.truncated_at_byte() >= 0) {
    summary.notes.push_back("final record cut short at byte " +
                            std::to_string(log.truncated_at_byte()) + " (end of file; discarded)");
  }
  return summary;
}

}  // namespace navtwin
