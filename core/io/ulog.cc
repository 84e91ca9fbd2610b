#include "core/io/ulog.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "core/io/input_error.h"
#include "core/io/ulog_format.h"
#include "core/io/ulog_time.h"
#include "core/io/ulog_topic.h"
#include "core/rotation.h"
#include "core/text.h"
#include "core/units.h"

namespace navtwin {
namespace {

using ulog::BaseType;

// Flag bits ('B'): incompat_flags[0] bit 0 = data appended; other bits are unknown to us.
constexpr std::uint8_t kIncompatDataAppended = 0x01;
constexpr std::size_t kFlagBitsSize = 40;  // compat[8], incompat[8], appended_offsets[3]
constexpr long long kFlagBitsOffset = 16;  // directly after the file header

std::string CString(const std::uint8_t* p, std::size_t n) {
  std::size_t len = 0;
  while (len < n && p[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(p), len);
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
    return InputError::AtByte(stream_.path(), message_.byte_offset, PrintableText(field, 128),
                              reason);
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
  std::map<std::string, std::size_t> format_sizes_;  // of the formats checked so far

 private:
  void CheckFormats();
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
  CheckFormats();  // a log with no subscription at all
  return false;
}

// Every format defined so far must resolve, subscribed or not (docs/formats.md). Checked
// before each subscription (the definitions precede the first one) and at the end.
void ULogFile::Impl::CheckFormats() {
  if (format_sizes_.size() == formats_.size()) return;
  for (const auto& entry : formats_) {
    if (format_sizes_.count(entry.first) == 0) {
      ulog::CheckFormat(entry.first, formats_, stream_.path(), &format_sizes_);
    }
  }
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
    throw Error(name, "format '" + PrintableText(name) + "' is defined twice");
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
    throw Error(key.name, "type '" + PrintableText(key.type) + "' is not a basic type");
  }
  const std::size_t count = key.array_length > 0 ? static_cast<std::size_t>(key.array_length) : 1;
  const std::size_t value_size = message_.payload.size() - value_at;
  const std::uint8_t* value = message_.payload.data() + value_at;
  if (type == BaseType::kChar) return CString(value, value_size);
  if (value_size != count * ulog::BaseTypeSize(type)) {
    throw Error(key.name, "value has " + std::to_string(value_size) + " bytes, type '" +
                              PrintableText(key.type) + "' needs " +
                              std::to_string(count * ulog::BaseTypeSize(type)));
  }
  std::string text;
  for (std::size_t i = 0; i < count; ++i) {
    if (i > 0) text += ",";
    text += ulog::FormatNumber(ulog::DecodeAsDouble(type, value + i * ulog::BaseTypeSize(type)));
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
    throw Error(key.name,
                "parameter type must be int32_t or float, got '" + PrintableText(key.type) + "'");
  }
  if (message_.payload.size() - value_at != 4) {
    throw Error(key.name, "value has " + std::to_string(message_.payload.size() - value_at) +
                              " bytes, needs 4");
  }
  const BaseType type = key.type == "float" ? BaseType::kFloat : BaseType::kInt32;
  parameters_[key.name] = ulog::DecodeAsDouble(type, message_.payload.data() + value_at);
}

void ULogFile::Impl::HandleSubscription() {
  CheckFormats();
  RequireSize(4, "subscription");
  ULogSubscription sub;
  sub.multi_id = message_.payload[0];
  sub.msg_id = static_cast<int>(ulog::DecodeUnsigned(message_.payload.data() + 1, 2));
  sub.topic.assign(message_.payload.begin() + 3, message_.payload.end());
  if (formats_.count(sub.topic) == 0) {
    throw Error("message_name", "subscription to unknown format '" + PrintableText(sub.topic) +
                                    "' (no 'F' message defines it)");
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
                    PrintableText(subscriptions_[it->second].topic) + "' has " +
                    std::to_string(layout.size) + " (" + std::to_string(layout.min_size) +
                    " without trailing padding)");
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
                "no such field in format '" + PrintableText(subscriptions_[current_].topic) + "'");
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
std::uint64_t ULogFile::start_time_us() const { return impl_->stream_.start_time_us(); }
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
// DescribeULog.
namespace {

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
  for (const ulog::Candidate& c : ulog::GnssCandidates()) {
    const ULogSubscription* sub = ulog::FindSubscription(subs, c);
    if (sub == nullptr) continue;
    const ulog::GnssFields f = ulog::GnssFieldsOf(*sub);
    notes->push_back("GNSS from " + sub->topic + ": height from " + f.height +
                     (f.ellipsoid ? " (WGS84 ellipsoid)" : " (MSL: no ellipsoid height logged)"));
    return;
  }
}

}  // namespace

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
    if (it != log.info().end()) {
      summary.notes.push_back(std::string(key) + ": " + PrintableText(it->second, 128));
    }
  }
  for (const ULogSubscription& sub : log.subscriptions()) {
    std::vector<std::string> fields;
    for (const ULogField& f : sub.fields) fields.push_back(f.Describe());
    const StreamTimes& st = times[sub.msg_id];
    summary.streams.push_back(StreamSummary::FromStats(sub.Label(), st.stats, std::move(fields)));
    AddTimeNotes(sub.Label(), st, &summary.notes);
  }
  summary.notes.push_back("dropouts: " + std::to_string(log.dropout_count()) + ", total " +
                          ulog::FormatNumber(log.dropout_total_s() * 1e3) + " ms");
  summary.notes.push_back("logged messages: " + std::to_string(log.logged_strings().size()));
  AddGnssNote(log.subscriptions(), &summary.notes);
  summary.notes.push_back("stream times above: seconds since boot; typed readers: " +
                          FindULogClock(path).Describe());
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
