// Tests of the PX4 ULog reader: synthetic files built by a tiny writer below, then
// the four real logs in px4-ulog/.
#include "core/io/ulog.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/ulog_time.h"
#include "tests/core/io/io_test_util.h"
#include "tests/core/io/ulog_writer.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_ulog_test {

using testing::ReadAllSamples;

// A file name under the test temp folder, unique to this process.
std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "/ulog_test_" + std::to_string(::getpid()) + "_" + name;
}

using ulog_writer::Bytes;
using ulog_writer::ULogWriter;

const char kSensorCombined[] =
    "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
    "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
    "uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t gyro_clipping;"
    "uint8_t accel_calibration_count;uint8_t gyro_calibration_count;";

Bytes ImuData(std::uint64_t t_us, float gyro_x, std::uint32_t gyro_dt_us, float acc_z,
              std::uint32_t acc_dt_us) {
  Bytes b;
  b.U64(t_us).F32(gyro_x).F32(0.f).F32(0.f).U32(gyro_dt_us).I32(0);
  b.F32(0.f).F32(0.f).F32(acc_z).U32(acc_dt_us).U8(0).U8(0).U8(0).U8(0);
  return b;
}

ULogWriter ImuLog() {
  ULogWriter w;
  w.FlagBits(0).Format(kSensorCombined).Subscribe(0, 0, "sensor_combined");
  return w;
}

bool HasNote(const FileSummary& summary, const std::string& text) {
  return std::any_of(summary.notes.begin(), summary.notes.end(),
                     [&](const std::string& n) { return n.find(text) != std::string::npos; });
}

const StreamSummary* FindStream(const FileSummary& summary, const std::string& name) {
  for (const StreamSummary& s : summary.streams) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

// Runs f, which must throw InputError; returns it.
template <typename F>
InputError CatchInputError(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return InputError("", 0, "", "");
}

// ---------------------------------------------------------------------------------------

TEST(ULogTest, NestedFormatArraysPaddingAndTwoInstances) {
  ULogWriter w;
  // "pair" uses the nested type before it is defined (allowed by the spec); the nested
  // padding is present in data, the trailing top-level padding is left out (as PX4 does).
  w.FlagBits(0)
      .Format(
          "my_topic:uint64_t timestamp;vec3[2] pair;char[8] label;int16_t count;uint8_t[6] "
          "_padding0;")
      .Format("vec3:float[3] v;uint8_t[4] _padding0;")
      .Subscribe(0, 0, "my_topic")
      .Subscribe(1, 1, "my_topic");
  auto data = [](std::uint64_t t, float base, std::int16_t count) {
    Bytes b;
    b.U64(t);
    for (int i = 0; i < 2; ++i)
      b.F32(base + 3 * i).F32(base + 3 * i + 1).F32(base + 3 * i + 2).Zeros(4);
    return b.Str("abc").Zeros(5).I16(count);
  };
  w.Data(0, data(100, 1.f, -7)).Data(1, data(150, 10.f, 3)).Data(0, data(200, 2.f, -8));
  const std::string path = w.Save("nested");

  ULogFile log(path);
  ASSERT_TRUE(log.NextOf("my_topic", 1));
  EXPECT_EQ(log.timestamp_us(), 150u);
  EXPECT_EQ(log.subscription().Label(), "my_topic[1]");
  EXPECT_DOUBLE_EQ(log.GetArray("pair[1].v", 2), 15.0);  // base + 3 + 2
  EXPECT_EQ(log.GetString("label"), "abc");
  EXPECT_DOUBLE_EQ(log.GetDouble("count"), 3.0);
  EXPECT_FALSE(log.HasField("_padding0"));
  std::vector<std::string> fields;
  for (const ULogField& f : log.subscription().fields) fields.push_back(f.Describe());
  EXPECT_EQ(fields,
            (std::vector<std::string>{"timestamp:uint64_t", "pair[0].v:float[3]",
                                      "pair[1].v:float[3]", "label:char[8]", "count:int16_t"}));
  ASSERT_TRUE(log.NextOf("my_topic", 0));
  EXPECT_EQ(log.timestamp_us(), 200u);
  EXPECT_DOUBLE_EQ(log.GetArray("pair[0].v", 0), 2.0);
  EXPECT_DOUBLE_EQ(log.GetDouble("count"), -8.0);
  EXPECT_EQ(CatchInputError([&] { log.GetDouble("pair[0].v"); }).field(), "my_topic.pair[0].v");
  EXPECT_EQ(CatchInputError([&] { log.GetArray("pair[0].v", 3); }).field(), "my_topic.pair[0].v");
  EXPECT_EQ(CatchInputError([&] { log.GetDouble("nope"); }).field(), "my_topic.nope");
  EXPECT_FALSE(log.Next());

  const FileSummary summary = DescribeULog(path);
  EXPECT_EQ(summary.kind, "ulog");
  ASSERT_EQ(summary.streams.size(), 2u);
  EXPECT_EQ(summary.streams[0].name, "my_topic");
  EXPECT_EQ(summary.streams[0].count, 2u);
  EXPECT_DOUBLE_EQ(summary.streams[0].t_first_s, 100e-6);
  EXPECT_DOUBLE_EQ(summary.streams[0].t_last_s, 200e-6);
  EXPECT_EQ(summary.streams[1].name, "my_topic[1]");
  EXPECT_EQ(summary.streams[1].count, 1u);
}

TEST(ULogTest, InfoParametersDropoutsAndLoggedStrings) {
  ULogWriter w;
  w.FlagBits(0)
      .InfoText("sys_name", "PX4")
      .InfoText("ver_hw", "TEST_BOARD")
      .Info("uint32_t ver_sw_release", Bytes().U32(0x010f01ff).data())
      .Param("float MC_ROLL_P", Bytes().F32(6.5f).data())
      .Param("int32_t SYS_AUTOSTART", Bytes().I32(4001).data())
      .Format("t:uint64_t timestamp;")
      .Subscribe(0, 0, "t")
      .Data(0, Bytes().U64(10))
      .Dropout(100)
      .Logged('6', 20, "[commander] armed")
      .Data(0, Bytes().U64(30))
      .Tagged('3', 7, 40, "tagged error")
      .Dropout(50)
      .Param("float MC_ROLL_P", Bytes().F32(7.0f).data())  // changed in flight
      .Message('X', "future message type");
  const std::string path = w.Save("info");

  ULogFile log(path);
  while (log.Next()) {
  }
  EXPECT_EQ(log.version(), 1);
  EXPECT_EQ(log.info().at("sys_name"), "PX4");
  EXPECT_EQ(log.info().at("ver_sw_release"), std::to_string(0x010f01ff));
  EXPECT_DOUBLE_EQ(log.parameters().at("MC_ROLL_P"), 7.0);
  EXPECT_DOUBLE_EQ(log.parameters().at("SYS_AUTOSTART"), 4001.0);
  ASSERT_EQ(log.logged_strings().size(), 2u);
  EXPECT_EQ(log.logged_strings()[0].level, 6);
  EXPECT_EQ(log.logged_strings()[0].tag, -1);
  EXPECT_EQ(log.logged_strings()[0].text, "[commander] armed");
  EXPECT_EQ(log.logged_strings()[1].level, 3);
  EXPECT_EQ(log.logged_strings()[1].tag, 7);
  EXPECT_EQ(log.logged_strings()[1].timestamp_us, 40u);
  EXPECT_EQ(log.dropout_count(), 2u);
  EXPECT_DOUBLE_EQ(log.dropout_total_s(), 0.150);
  EXPECT_EQ(log.unknown_message_count(), 1u);

  const FileSummary summary = DescribeULog(path);
  EXPECT_TRUE(HasNote(summary, "ULog version 1"));
  EXPECT_TRUE(HasNote(summary, "sys_name: PX4"));
  EXPECT_TRUE(HasNote(summary, "ver_hw: TEST_BOARD"));
  EXPECT_TRUE(HasNote(summary, "dropouts: 2, total 150 ms"));
  EXPECT_TRUE(HasNote(summary, "logged messages: 2"));
  EXPECT_TRUE(HasNote(summary, "unknown type: 1"));
  EXPECT_FALSE(HasNote(summary, "cut short"));
}

TEST(ULogTest, ImuIncrementsFromIntegralTimesAndTimeTags) {
  ULogWriter w = ImuLog();
  w.Data(0, ImuData(1'000'000, 0.5f, 4000, -9.8f, 4100))
      .Data(0, ImuData(1'005'000, 0.25f, 5000, -9.0f, 5000))
      .Data(0, ImuData(1'009'000, 1.0f, 4000, -8.0f, 0));  // accel integral missing: rate * dt
  auto reader = OpenULogImu(w.Save("imu"));
  const std::vector<ImuSample> s = ReadAllSamples(*reader);
  ASSERT_EQ(s.size(), 3u);
  // Tolerances: the rates are floats (e.g. 0.5f is exact, -9.8f is not: 4e-7 relative).
  EXPECT_DOUBLE_EQ(s[0].t_s, 1.0);
  EXPECT_DOUBLE_EQ(s[0].dt_s, 0.004);  // first sample: gyro_integral_dt
  EXPECT_DOUBLE_EQ(s[0].dtheta_b_rad.x(), 0.5 * 0.004);
  EXPECT_NEAR(s[0].dv_b_mps.z(), -9.8 * 0.0041, 1e-8);
  EXPECT_NEAR(s[1].dt_s, 0.005, 1e-12);  // from time tags (1e-12: decimal seconds in double)
  EXPECT_DOUBLE_EQ(s[1].dtheta_b_rad.x(), 0.25 * 0.005);
  EXPECT_NEAR(s[2].dt_s, 0.004, 1e-12);
  EXPECT_NEAR(s[2].dv_b_mps.z(), -8.0 * 0.004, 1e-12);
}

TEST(ULogTest, ImuOldFloatIntegralSecondsAndMissingIntegral) {
  // Old PX4 (e.g. sample.ulg) logs the integration times as float seconds.
  auto data = [](std::uint64_t t_us) {
    Bytes b;
    b.U64(t_us).F32(2.f).F32(0.f).F32(0.f).F32(0.004f);  // gyro_rad, gyro_integral_dt [s]
    return b.F32(0.f).F32(0.f).F32(-10.f);               // accelerometer_m_s2
  };
  ULogWriter w(0);
  w.Format(
       "sensor_combined:uint64_t timestamp;float[3] gyro_rad;float gyro_integral_dt;"
       "float[3] accelerometer_m_s2;")
      .Subscribe(0, 0, "sensor_combined")
      .Data(0, data(2'000'000))
      .Data(0, data(2'004'000));
  auto reader = OpenULogImu(w.Save("imu_old"));
  const std::vector<ImuSample> s = ReadAllSamples(*reader);
  ASSERT_EQ(s.size(), 2u);
  // 1e-9 (1e-8 for dv): the float 0.004f differs from 0.004 by 1.9e-10 s.
  EXPECT_NEAR(s[0].dt_s, 0.004, 1e-9);
  EXPECT_NEAR(s[0].dtheta_b_rad.x(), 2.0 * 0.004, 1e-9);
  // No accelerometer_integral_dt field: dv = rate * dt_s (first sample: gyro integral).
  EXPECT_NEAR(s[0].dv_b_mps.z(), -10.0 * 0.004, 1e-8);
  EXPECT_NEAR(s[1].dv_b_mps.z(), -10.0 * 0.004, 1e-12);

  // No integral times at all: the first sample only starts the clock.
  ULogWriter z = ImuLog();
  z.Data(0, ImuData(1'000'000, 1.f, 0, -9.f, 0)).Data(0, ImuData(1'005'000, 1.f, 0, -9.f, 0));
  auto zr = OpenULogImu(z.Save("imu_zero"));
  const std::vector<ImuSample> zs = ReadAllSamples(*zr);
  ASSERT_EQ(zs.size(), 1u);
  EXPECT_NEAR(zs[0].dtheta_b_rad.x(), 0.005, 1e-12);  // 1 rad/s * 5 ms from time tags
}

TEST(ULogTest, ImplausibleRatesAndFieldsNameByteOffsetAndField) {
  // A float gyro rate of 1e16 rad/s (finite, absurd): refused at its record.
  ULogWriter w = ImuLog();
  w.Data(0, ImuData(1'000'000, 0.5f, 4000, -9.8f, 4000));
  const long long bad_at = w.offset();
  w.Data(0, ImuData(1'005'000, 1e16f, 5000, -9.8f, 5000));
  auto reader = OpenULogImu(w.Save("imu_absurd"));
  ImuSample s;
  ASSERT_TRUE(reader->Next(&s));
  const InputError e = CatchInputError([&] { reader->Next(&s); });
  EXPECT_EQ(e.byte_offset(), bad_at);
  EXPECT_EQ(e.field(), "sensor_combined.gyro_rad");
  EXPECT_NE(std::string(e.what()).find("implausible angular rate"), std::string::npos) << e.what();

  ULogWriter m;
  m.Format("sensor_mag:uint64_t timestamp;float x;float y;float z;")
      .Subscribe(0, 0, "sensor_mag")
      .Data(0, Bytes().U64(800).F32(0.5f).F32(3e30f).F32(-0.25f));
  auto mag = OpenULogMag(m.Save("mag_absurd"));
  MagSample ms;
  const InputError em = CatchInputError([&] { mag->Next(&ms); });
  EXPECT_EQ(em.field(), "sensor_mag.y");
  EXPECT_NE(std::string(em.what()).find("implausible magnetic field"), std::string::npos) << em.what();
}

TEST(ULogTest, RepeatedTimeIsSkippedBackwardsTimeNamesByteOffset) {
  ULogWriter w = ImuLog();
  w.Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000))
      .Data(0, ImuData(1'005'000, 0.f, 5000, -9.8f, 5000))
      .Data(0, ImuData(1'005'000, 0.f, 5000, -9.8f, 5000));  // repeated: skipped
  const long long backwards_at = w.offset();
  w.Data(0, ImuData(1'004'000, 0.f, 5000, -9.8f, 5000));
  const std::string path = w.Save("backwards");

  auto reader = OpenULogImu(path);
  ImuSample s;
  ASSERT_TRUE(reader->Next(&s));
  ASSERT_TRUE(reader->Next(&s));
  const InputError e = CatchInputError([&] { reader->Next(&s); });
  EXPECT_EQ(e.byte_offset(), backwards_at);
  EXPECT_EQ(e.field(), "sensor_combined.timestamp");
  EXPECT_NE(std::string(e.what()).find("byte " + std::to_string(backwards_at)), std::string::npos);

  // DescribeULog reports instead of failing.
  const FileSummary summary = DescribeULog(path);
  EXPECT_EQ(summary.streams.at(0).count, 4u);
  EXPECT_TRUE(HasNote(summary, "sensor_combined: 1 repeated timestamps"));
  EXPECT_TRUE(HasNote(summary, "sensor_combined: 1 timestamps going backwards"));
}

TEST(ULogTest, TruncatedFinalRecordIsAcceptedWithNote) {
  ULogWriter w = ImuLog();
  for (int i = 0; i < 4; ++i) w.Data(0, ImuData(1'000'000 + 5000 * i, 0.f, 5000, -9.8f, 5000));
  const long long cut_at = w.offset();
  // The header of the message and 10 of its 50 bytes, as a power loss leaves it.
  w.Raw(Bytes().U16(50).U8('D').U16(0).Zeros(8).data());
  const std::string path = w.Save("truncated");

  auto reader = OpenULogImu(path);
  EXPECT_EQ(ReadAllSamples(*reader).size(), 4u);
  const FileSummary summary = DescribeULog(path);
  EXPECT_EQ(summary.streams.at(0).count, 4u);
  EXPECT_TRUE(HasNote(summary, "final record cut short at byte " + std::to_string(cut_at)));

  // A cut inside the 3-byte message header is a truncation too.
  ULogWriter h = ImuLog();
  h.Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
  const long long header_cut_at = h.offset();
  h.Raw(std::string(2, '\x30'));
  ULogFile log(h.Save("truncated_header"));
  EXPECT_TRUE(log.Next());
  EXPECT_FALSE(log.Next());
  EXPECT_EQ(log.truncated_at_byte(), header_cut_at);
}

TEST(ULogTest, BadMagicNamesByteZero) {
  const std::string path = TempPath("bad_magic.ulg");
  std::ofstream(path, std::ios::binary) << "ULog\x01\x13\x35\x01" << std::string(8, '\0');
  for (const InputError& e : {CatchInputError([&] { DescribeULog(path); }),
                              CatchInputError([&] { OpenULogImu(path); })}) {
    EXPECT_EQ(e.byte_offset(), 0);
    EXPECT_EQ(e.field(), "magic");
    EXPECT_EQ(e.file(), path);
  }
  const std::string empty = TempPath("empty.ulg");
  std::ofstream(empty, std::ios::binary).close();
  EXPECT_EQ(CatchInputError([&] { ULogFile log(empty); }).field(), "header");
}

TEST(ULogTest, DataForUnknownMsgIdNamesByteOffset) {
  ULogWriter w = ImuLog();
  w.Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
  const long long bad_at = w.offset();
  w.Data(3, ImuData(1'005'000, 0.f, 5000, -9.8f, 5000));
  const InputError e = CatchInputError([&] { DescribeULog(w.Save("unknown_id")); });
  EXPECT_EQ(e.byte_offset(), bad_at);
  EXPECT_EQ(e.field(), "msg_id");

  // After an unsubscription ('R') the msg_id is unknown again.
  ULogWriter r = ImuLog();
  r.Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000)).Message('R', Bytes().U16(0).data());
  const long long removed_at = r.offset();
  r.Data(0, ImuData(1'005'000, 0.f, 5000, -9.8f, 5000));
  EXPECT_EQ(CatchInputError([&] { DescribeULog(r.Save("removed_id")); }).byte_offset(), removed_at);
}

TEST(ULogTest, MalformedDefinitionsAndSizesNameByteOffsetAndField) {
  {  // subscription to a format no 'F' message defines
    ULogWriter w;
    w.FlagBits(0).Format(kSensorCombined);
    const long long at = w.offset();
    w.Subscribe(0, 0, "sensor_gyro");
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("unknown_format")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "message_name");
  }
  {  // a field type that is neither basic nor defined: reported at its 'F' message
    ULogWriter w;
    w.FlagBits(0);
    const long long at = w.offset();
    w.Format("t:uint64_t timestamp;quaternion q;").Subscribe(0, 0, "t");
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("unknown_type")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "t.q");
  }
  {  // circular nesting
    ULogWriter w;
    w.FlagBits(0).Format("a:uint64_t timestamp;b x;").Format("b:a y;").Subscribe(0, 0, "a");
    EXPECT_NE(std::string(CatchInputError([&] { DescribeULog(w.Save("circular")); }).what())
                  .find("circular"),
              std::string::npos);
  }
  {  // data message shorter than its format (not at the end of the file)
    ULogWriter w = ImuLog();
    const long long at = w.offset();
    w.Data(0, Bytes().U64(5)).Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("short_data")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "sensor_combined");
  }
  {  // a dropout message too small for its duration
    ULogWriter w = ImuLog();
    const long long at = w.offset();
    w.Message('O', "x").Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("short_dropout")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "msg_size");
  }
  {  // malformed format text
    ULogWriter w;
    w.FlagBits(0);
    const long long at = w.offset();
    w.Format("t:uint64_t timestamp;float[x] v;");
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("bad_array")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "t field 2");
  }
}

TEST(ULogTest, FormatLargerThanADataMessageIsRefusedAtItsFormatMessage) {
  // 2 x 40000 bytes: more than the 65535 bytes a data message can hold.
  ULogWriter w;
  w.FlagBits(0).Format("inner:uint8_t[40000] v;");
  const long long at = w.offset();
  w.Format("outer:uint64_t timestamp;inner[2] a;").Subscribe(0, 0, "outer");
  const InputError e = CatchInputError([&] { DescribeULog(w.Save("too_big")); });
  EXPECT_EQ(e.byte_offset(), at);
  EXPECT_EQ(e.field(), "outer.a");
  EXPECT_NE(std::string(e.what()).find("65535"), std::string::npos) << e.what();
}

TEST(ULogTest, NestedArrayFormatBombIsRefusedWithoutExpandingIt) {
  // 99999 x 99999 x 99999 elements if flattened: refused at the first format that is
  // too large, before any leaf is built.
  ULogWriter w;
  w.FlagBits(0).Format("leaf:uint8_t v;");
  const long long at = w.offset();
  w.Format("inner:leaf[99999] e;")
      .Format("middle:inner[99999] i;")
      .Format("bomb:uint64_t timestamp;middle[99999] m;")
      .Subscribe(0, 0, "bomb");
  const InputError e = CatchInputError([&] { DescribeULog(w.Save("bomb")); });
  EXPECT_EQ(e.byte_offset(), at);
  EXPECT_EQ(e.field(), "inner.e");
}

TEST(ULogTest, CircularOrUndefinedFormatIsAnErrorEvenWithoutSubscription) {
  {
    ULogWriter w = ImuLog();
    w.Format("a:uint64_t timestamp;b x;");
    const long long at = w.offset();  // "b" closes the loop
    w.Format("b:a y;").Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("circular")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "b.y");
    EXPECT_NE(std::string(e.what()).find("circular"), std::string::npos) << e.what();
  }
  {
    ULogWriter w;
    w.FlagBits(0);
    const long long at = w.offset();
    w.Format("t:uint64_t timestamp;quaternion q;").Format(kSensorCombined);
    w.Subscribe(0, 0, "sensor_combined").Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("undefined")); });
    EXPECT_EQ(e.byte_offset(), at);
    EXPECT_EQ(e.field(), "t.q");
  }
  {  // definitions only, no data section at all
    ULogWriter w;
    w.FlagBits(0).Format("a:uint64_t timestamp;b x;");
    const long long at = w.offset();
    w.Format("b:a y;");
    EXPECT_EQ(CatchInputError([&] { DescribeULog(w.Save("circular_only")); }).byte_offset(), at);
  }
}

TEST(ULogTest, ErrorMessagesAndNotesShowBinaryTextEscapedAndShortened) {
  auto printable = [](const std::string& text) {
    return std::all_of(text.begin(), text.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
  };
  {  // a subscription whose topic is binary garbage
    ULogWriter w = ImuLog();
    w.Subscribe(0, 1, std::string("bad\x01\xff\ntopic"));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("binary_topic")); });
    EXPECT_TRUE(printable(e.what())) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad\\x01\\xff\\x0atopic"), std::string::npos) << e.what();
  }
  {  // a malformed format whose name and text are long binary garbage
    ULogWriter w;
    w.FlagBits(0).Format(std::string(2000, '\x07') + ":uint64_t timestamp;float[x] v;");
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("binary_format")); });
    EXPECT_TRUE(printable(e.what())) << e.what();
    EXPECT_LT(std::string(e.what()).size(), 600u) << e.what();
  }
  {  // a format without a colon: the whole text is echoed
    ULogWriter w;
    w.FlagBits(0).Format(std::string("\x1b[2J") + std::string(3000, 'z'));
    const InputError e = CatchInputError([&] { DescribeULog(w.Save("no_colon")); });
    EXPECT_TRUE(printable(e.what())) << e.what();
    EXPECT_LT(std::string(e.what()).size(), 600u) << e.what();
  }
  {  // info text shown by DescribeULog
    ULogWriter w = ImuLog();
    w.InfoText("sys_name", "PX4\x1b[31m\x01");
    w.Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000));
    const FileSummary summary = DescribeULog(w.Save("binary_info"));
    EXPECT_TRUE(HasNote(summary, "sys_name: PX4\\x1b[31m\\x01"));
    for (const std::string& note : summary.notes) EXPECT_TRUE(printable(note)) << note;
  }
}

TEST(ULogTest, UnknownIncompatibleFlagIsRefused) {
  ULogWriter w;
  w.FlagBits(0x02).Format(kSensorCombined);
  const InputError e = CatchInputError([&] { DescribeULog(w.Save("incompat")); });
  EXPECT_EQ(e.byte_offset(), 16);
  EXPECT_EQ(e.field(), "incompat_flags");
}

TEST(ULogTest, AppendedDataAfterACutMessageIsRead) {
  // The logger stopped inside a message; crash data were appended at a known offset.
  auto build = [](std::uint64_t appended_offset, long long* appended_at) {
    ULogWriter w;
    w.FlagBits(0x01, appended_offset)
        .Format(kSensorCombined)
        .Subscribe(0, 0, "sensor_combined")
        .Data(0, ImuData(1'000'000, 0.f, 5000, -9.8f, 5000))
        .Raw(Bytes().U16(50).U8('D').U16(0).Zeros(20).data());  // cut after 25 of 53 bytes
    *appended_at = w.offset();
    return w.Data(0, ImuData(1'010'000, 0.f, 5000, -9.8f, 5000));
  };
  long long appended_at = 0;
  build(0, &appended_at);  // a first pass finds the offset (sizes do not depend on it)
  const std::string path =
      build(static_cast<std::uint64_t>(appended_at), &appended_at).Save("appended");
  auto reader = OpenULogImu(path);
  const std::vector<ImuSample> s = ReadAllSamples(*reader);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_NEAR(s[1].dt_s, 0.010, 1e-12);
  EXPECT_TRUE(
      HasNote(DescribeULog(path), "appended data from byte " + std::to_string(appended_at)));
}

// vehicle_gps_position with the old integer field names (PX4 <= 1.13) and the new
// float names; both files hold the same fix, plus one 2D fix that must be skipped.
std::string GpsLog(bool new_names, const std::string& name) {
  ULogWriter w;
  if (new_names) {
    w.Format(
        "vehicle_gps_position:uint64_t timestamp;double latitude_deg;double longitude_deg;"
        "double altitude_msl_m;double altitude_ellipsoid_m;float s_variance_m_s;float eph;"
        "float epv;float vel_n_m_s;float vel_e_m_s;float vel_d_m_s;uint8_t fix_type;"
        "bool vel_ned_valid;uint8_t satellites_used;uint8_t[5] _padding0;");
  } else {
    w.Format(
        "vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;"
        "int32_t alt_ellipsoid;float s_variance_m_s;float eph;float epv;float vel_n_m_s;"
        "float vel_e_m_s;float vel_d_m_s;uint8_t fix_type;bool vel_ned_valid;"
        "uint8_t satellites_used;uint8_t[5] _padding0;");
  }
  w.Subscribe(0, 0, "vehicle_gps_position");
  for (std::uint8_t fix : {2, 3}) {
    Bytes b;
    b.U64(fix == 2 ? 40'000'000 : 40'200'000);
    if (new_names) {
      b.F64(53.7156777).F64(9.8207834).F64(11.077).F64(56.124);
    } else {
      b.I32(537156777).I32(98207834).I32(11077).I32(56124);
    }
    b.F32(0.161f).F32(0.77f).F32(1.438f).F32(0.011f).F32(-0.011f).F32(0.002f).U8(fix).U8(1).U8(12);
    w.Data(0, b);
  }
  return w.Save(name);
}

TEST(ULogTest, GnssOldIntegerAndNewFloatFieldsGiveTheSameSample) {
  std::vector<GnssSample> samples;
  for (bool new_names : {false, true}) {
    const std::string path = GpsLog(new_names, new_names ? "gps_new" : "gps_old");
    auto reader = OpenULogGnss(path);
    GnssSample s;
    ASSERT_TRUE(reader->Next(&s));  // the 2D fix is skipped
    samples.push_back(s);
    EXPECT_FALSE(reader->Next(&s));
    EXPECT_TRUE(HasNote(
        DescribeULog(path),
        "height from " + std::string(new_names ? "altitude_ellipsoid_m" : "alt_ellipsoid")));
  }
  const GnssSample& a = samples[0];
  const GnssSample& b = samples[1];
  EXPECT_DOUBLE_EQ(a.t_s, 40.2);
  // 1e-15 rad and 1e-12 m: 1e-7 deg and mm scaling rounds differently from the decimal
  // doubles of the new fields (a few ulp).
  EXPECT_NEAR(a.lat_rad, 53.7156777 * M_PI / 180.0, 1e-15);
  EXPECT_NEAR(a.lat_rad, b.lat_rad, 1e-15);
  EXPECT_NEAR(a.lon_rad, b.lon_rad, 1e-15);
  EXPECT_NEAR(a.h_m, 56.124, 1e-12);
  EXPECT_NEAR(a.h_m, b.h_m, 1e-12);
  EXPECT_EQ(a.pos_std_ned_m, b.pos_std_ned_m);
  EXPECT_FLOAT_EQ(static_cast<float>(a.pos_std_ned_m.x()), 0.77f);
  EXPECT_FLOAT_EQ(static_cast<float>(a.pos_std_ned_m.z()), 1.438f);
  EXPECT_TRUE(a.has_velocity && b.has_velocity);
  EXPECT_EQ(a.v_n_mps, b.v_n_mps);
  EXPECT_FLOAT_EQ(static_cast<float>(a.vel_std_ned_mps.y()), 0.161f);
  EXPECT_EQ(a.vel_std_ned_mps, b.vel_std_ned_mps);
  EXPECT_EQ(a.quality, 3);
  EXPECT_EQ(b.quality, 3);
  EXPECT_EQ(a.num_sats, 12);
  EXPECT_EQ(b.num_sats, 12);
}

TEST(ULogTest, MagnetometerGaussToMicroteslaWithSensorMagFallback) {
  ULogWriter w;
  w.Format(
       "vehicle_magnetometer:uint64_t timestamp;uint32_t device_id;float[3] magnetometer_ga;"
       "uint8_t[4] _padding0;")
      .Subscribe(0, 0, "vehicle_magnetometer")
      .Data(0, Bytes().U64(500).U32(1).F32(0.25f).F32(-0.5f).F32(0.125f));
  auto reader = OpenULogMag(w.Save("mag"));
  MagSample m;
  ASSERT_TRUE(reader->Next(&m));
  EXPECT_DOUBLE_EQ(m.t_s, 500e-6);
  EXPECT_EQ(m.m_b_uT, Eigen::Vector3d(25.0, -50.0, 12.5));  // exact: binary fractions
  EXPECT_FALSE(reader->Next(&m));

  ULogWriter r;
  r.Format("sensor_mag:uint64_t timestamp;float x;float y;float z;")
      .Subscribe(1, 0, "sensor_mag")  // instance 1 is not used
      .Subscribe(0, 1, "sensor_mag")
      .Data(0, Bytes().U64(700).F32(9.f).F32(9.f).F32(9.f))
      .Data(1, Bytes().U64(800).F32(0.5f).F32(0.25f).F32(-0.25f));
  auto raw = OpenULogMag(r.Save("sensor_mag"));
  ASSERT_TRUE(raw->Next(&m));
  EXPECT_DOUBLE_EQ(m.t_s, 800e-6);
  EXPECT_EQ(m.m_b_uT, Eigen::Vector3d(50.0, 25.0, -25.0));
  EXPECT_FALSE(raw->Next(&m));
}

TEST(ULogTest, BarometerFromVehicleAirData) {
  ULogWriter w;
  w.Format(
       "vehicle_air_data:uint64_t timestamp;float baro_alt_meter;float baro_temp_celcius;"
       "float baro_pressure_pa;")
      .Subscribe(0, 0, "vehicle_air_data")
      .Data(0, Bytes().U64(2'000'000).F32(12.5f).F32(21.25f).F32(101000.f));
  auto reader = OpenULogBaro(w.Save("baro"));
  BaroSample b;
  ASSERT_TRUE(reader->Next(&b));
  EXPECT_DOUBLE_EQ(b.t_s, 2.0);
  EXPECT_DOUBLE_EQ(b.altitude_m, 12.5);
  EXPECT_DOUBLE_EQ(b.temperature_degC, 21.25);
  EXPECT_DOUBLE_EQ(b.pressure_pa, 101000.0);
  EXPECT_FALSE(reader->Next(&b));
  // A log without any barometer topic: the error names the missing topic.
  ULogWriter none = ImuLog();
  EXPECT_NE(CatchInputError([&] { OpenULogBaro(none.Save("no_baro")); })
                .reason()
                .find("vehicle_air_data"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------
// Real logs (px4-ulog/). Counts and median rates were measured once and are exact
// (the files do not change); the README's nominal rates are checked with a tolerance.

struct RealLog {
  const char* file;
  std::size_t streams;        // subscriptions (topic instances)
  std::size_t imu_count;      // sensor_combined messages
  double nominal_imu_hz;      // README: samples per second over the record
  double imu_median_rate_hz;  // 1 / median interval, as DescribeULog reports it
  const char* dropout_note;
};

double MeanRate(const StreamSummary& s) {
  return static_cast<double>(s.count - 1) / (s.t_last_s - s.t_first_s);
}

TEST(ULogRealDataTest, AllLogsDescribeAndReadImu) {
  const RealLog logs[] = {
      {"battery_brownout.ulg", 109, 16814, 221.0, 221.680331, "dropouts: 0, total 0 ms"},
      {"ekf_failure.ulg", 95, 15843, 199.0, 200.000004, "dropouts: 0, total 0 ms"},
      {"gps_interference.ulg", 122, 12321, 198.0, 197.823934, "dropouts: 0, total 0 ms"},
      {"sample.ulg", 43, 17070, 248.0, 249.999988, "dropouts: 4, total 119 ms"},
  };
  for (const RealLog& log : logs) {
    const std::string path = testing::DataPath(std::string("px4-ulog/") + log.file);
    NAVTWIN_REQUIRE_DATA(path);
    SCOPED_TRACE(log.file);
    const FileSummary summary = DescribeULog(path);
    const StreamSummary* imu = FindStream(summary, "sensor_combined");
    ASSERT_NE(imu, nullptr);
    std::printf(
        "%s: %zu streams, sensor_combined %zu samples, %.3f s, median %.6f Hz, mean %.3f Hz\n",
        log.file, summary.streams.size(), imu->count, imu->t_last_s - imu->t_first_s, imu->rate_hz,
        MeanRate(*imu));
    for (const std::string& note : summary.notes) std::printf("  note: %s\n", note.c_str());
    EXPECT_EQ(summary.streams.size(), log.streams);
    EXPECT_EQ(imu->count, log.imu_count);
    EXPECT_TRUE(HasNote(summary, log.dropout_note));
    // 1e-5 Hz: the rates were printed with 6 decimals.
    EXPECT_NEAR(imu->rate_hz, log.imu_median_rate_hz, 1e-5);
    // +-2 Hz: the README rates are rounded and count/span includes logging gaps.
    EXPECT_NEAR(MeanRate(*imu), log.nominal_imu_hz, 2.0);
    EXPECT_FALSE(HasNote(summary, "cut short"));

    auto reader = OpenULogImu(path);
    const std::vector<ImuSample> samples = ReadAllSamples(*reader);
    EXPECT_EQ(samples.size(), log.imu_count);
    ASSERT_FALSE(samples.empty());
    // DescribeULog lists boot times; the reader maps them through the log's clock (GPS
    // time for ekf_failure.ulg). 1e-9 s: rounding of the ~1e5 s times of week.
    const double shift_s = static_cast<double>(FindULogClock(path).shift_us) * 1e-6;
    EXPECT_NEAR(samples.front().t_s - shift_s, imu->t_first_s, 1e-9);
    EXPECT_NEAR(samples.back().t_s - shift_s, imu->t_last_s, 1e-9);
  }
}

TEST(ULogRealDataTest, EkfFailureRatesAndGnss) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const FileSummary summary = DescribeULog(path);
  const StreamSummary* imu = FindStream(summary, "sensor_combined");
  const StreamSummary* gps = FindStream(summary, "vehicle_gps_position");
  ASSERT_TRUE(imu != nullptr && gps != nullptr);
  // +-2 Hz on the median rate: the IMU interval jitters between 4.875 and 5.125 ms.
  EXPECT_NEAR(imu->rate_hz, 199.0, 2.0);
  // Sample count consistent with the 79.5 s span at 199 Hz (+-1 %: rounding of both).
  EXPECT_NEAR(static_cast<double>(imu->count), 79.5 * 199.0, 0.01 * 79.5 * 199.0);
  // +-0.2 Hz: GPS messages come at 200 ms +- receiver jitter.
  EXPECT_NEAR(gps->rate_hz, 5.0, 0.2);
  EXPECT_EQ(gps->count, 397u);
  EXPECT_NE(FindStream(summary, "sensor_mag[1]"), nullptr);

  auto reader = OpenULogGnss(path);
  GnssSample s;
  std::size_t n = 0;
  double min_eph = 1e9, max_eph = 0.0;
  while (reader->Next(&s)) {
    ++n;
    EXPECT_GE(s.quality, 3);
    min_eph = std::min(min_eph, s.pos_std_ned_m.x());
    max_eph = std::max(max_eph, s.pos_std_ned_m.x());
  }
  std::printf("ekf_failure: %zu GNSS samples with fix >= 3, eph %.3f..%.3f m\n", n, min_eph,
              max_eph);
  EXPECT_EQ(n, 397u);  // every message has fix 3 or 4
  // README: eph 0.5-0.8 m (0.05 m: rounding of the README figures).
  EXPECT_GT(min_eph, 0.45);
  EXPECT_LT(max_eph, 0.85);
}

TEST(ULogRealDataTest, BatteryBrownoutSpecificForceOnTheGround) {
  const std::string path = testing::DataPath("px4-ulog/battery_brownout.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  auto reader = OpenULogImu(path);
  ImuSample s;
  ASSERT_TRUE(reader->Next(&s));
  const double t0 = s.t_s;
  double sum = 0.0;
  int n = 0;
  do {
    sum += s.dv_b_mps.norm() / s.dt_s;
    ++n;
  } while (reader->Next(&s) && s.t_s < t0 + 1.0);
  std::printf("battery_brownout: mean |f| over the first second %.4f m/s^2 (%d samples)\n", sum / n,
              n);
  // 0.3 m/s^2: a unit or scale error in integral_dt would be off by 1e3 or 1e6; the rest
  // is accelerometer bias and idle vibration.
  EXPECT_NEAR(sum / n, 9.81, 0.3);
}

TEST(ULogRealDataTest, MagnetometerBarometerAndGnssSources) {
  const std::string sample = testing::DataPath("px4-ulog/sample.ulg");
  const std::string ekf = testing::DataPath("px4-ulog/ekf_failure.ulg");
  const std::string gps_interference = testing::DataPath("px4-ulog/gps_interference.ulg");
  NAVTWIN_REQUIRE_DATA(sample);
  NAVTWIN_REQUIRE_DATA(ekf);
  NAVTWIN_REQUIRE_DATA(gps_interference);
  std::size_t counts[3] = {0, 0, 0};
  double mean_norm_uT = 0.0;
  {
    auto mag = OpenULogMag(sample);  // old log: sensor_combined.magnetometer_ga
    MagSample m;
    while (mag->Next(&m)) ++counts[0];
    auto ekf_mag = OpenULogMag(ekf);  // vehicle_magnetometer
    while (ekf_mag->Next(&m)) {
      ++counts[1];
      mean_norm_uT += m.m_b_uT.norm();
    }
    mean_norm_uT /= static_cast<double>(counts[1]);
    auto baro = OpenULogBaro(ekf);
    BaroSample b;
    while (baro->Next(&b)) ++counts[2];
    // sample.ulg's sensor_combined has baro fields, but every baro_timestamp_relative
    // says "no sample" (the log notes "no barometer found").
    auto no_baro = OpenULogBaro(sample);
    EXPECT_FALSE(no_baro->Next(&b));
    // gps_interference's newer vehicle_air_data logs ambient_temperature instead.
    auto newer = OpenULogBaro(gps_interference);
    ASSERT_TRUE(newer->Next(&b));
    EXPECT_TRUE(std::isfinite(b.temperature_degC) && std::isfinite(b.pressure_pa));
    // Its 312 GPS messages all have fix_type 0: no GNSS samples.
    auto gnss = OpenULogGnss(gps_interference);
    GnssSample g;
    EXPECT_FALSE(gnss->Next(&g));
  }
  std::printf("sample mag %zu, ekf_failure mag %zu (mean |B| %.2f uT), baro %zu\n", counts[0],
              counts[1], mean_norm_uT, counts[2]);
  EXPECT_EQ(counts[0], 6759u);
  EXPECT_EQ(counts[1], 159u);
  EXPECT_EQ(counts[2], 399u);
  // Earth's field in northern Germany is about 50 uT; 25..65 allows calibration and
  // motor interference (a gauss/tesla slip would be off by 100x).
  EXPECT_GT(mean_norm_uT, 25.0);
  EXPECT_LT(mean_norm_uT, 65.0);
}

}  // namespace io_ulog_test
}  // namespace navtwin
