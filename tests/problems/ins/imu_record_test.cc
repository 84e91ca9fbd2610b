// ImuRecord (problems/ins/imu_record.h): a record in memory and the same record streamed
// give the same samples on every pass; a streamed record keeps only the head asked for,
// reads its source once on the first pass, again on later ones, and knows its end, length
// and bridged gaps only once a pass has reached the end.
#include <cstddef>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/sample_reader.h"
#include "problems/ins/imu_gaps.h"
#include "problems/ins/imu_record.h"

namespace navtwin::ins {
namespace ins_imu_record_test {

/// Samples at 100 Hz from t = 0.01 s; sample `gap_before` (when >= 0) follows a gap of 3
/// intervals.
std::vector<ImuSample> Samples(std::size_t n, long gap_before = -1) {
  std::vector<ImuSample> out;
  double t = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double dt = static_cast<long>(k) == gap_before ? 0.03 : 0.01;
    t += dt;
    ImuSample s;
    s.t_s = t;
    s.dt_s = dt;
    s.dtheta_b_rad = Eigen::Vector3d(1e-3 * k, 0.0, -1e-3);
    s.dv_b_mps = Eigen::Vector3d(0.0, 0.02, -0.098);
    out.push_back(s);
  }
  return out;
}

class VectorReader final : public ImuReader {
 public:
  explicit VectorReader(const std::vector<ImuSample>* samples) : samples_(samples) {}
  bool Next(ImuSample* s) override {
    if (next_ == samples_->size()) return false;
    *s = (*samples_)[next_++];
    return true;
  }
  const std::string& path() const override { return path_; }

 private:
  const std::vector<ImuSample>* samples_;
  std::size_t next_ = 0;
  std::string path_ = "imu.txt";
};

/// A streamed record over `source` through the gap bridge, counting the times it opens it.
ImuRecord StreamedOver(const std::vector<ImuSample>* source, int* opens) {
  return ImuRecord::Streamed([source, opens](std::size_t* bridged) {
    ++*opens;
    return GapBridgingImuReader(std::make_unique<VectorReader>(source), 1.0, "max_bridge_gap_s", 0.0, bridged);
  });
}

std::vector<ImuSample> Pass(const ImuRecord& record) {
  const std::unique_ptr<ImuReader> reader = record.Read();
  return ReadAll(*reader);
}

void ExpectSame(const std::vector<ImuSample>& a, const std::vector<ImuSample>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].t_s, b[k].t_s) << k;
    EXPECT_EQ(a[k].dt_s, b[k].dt_s) << k;
    EXPECT_EQ(a[k].dtheta_b_rad, b[k].dtheta_b_rad) << k;
    EXPECT_EQ(a[k].dv_b_mps, b[k].dv_b_mps) << k;
  }
}

TEST(ImuRecord, InMemoryKnowsEverythingAndReplaysItsSamples) {
  const std::vector<ImuSample> samples = Samples(50);
  const ImuRecord record(samples, 2);
  EXPECT_FALSE(record.streamed());
  EXPECT_TRUE(record.end_known());
  EXPECT_EQ(record.size(), 50u);
  EXPECT_EQ(record.bridged_gaps(), 2u);
  EXPECT_EQ(record.known_end_s(), samples.back().t_s);
  EXPECT_EQ(record.Head(0.1).size(), 50u);  // in memory: every sample
  EXPECT_NEAR(record.begin_s(), 0.0, 1e-15);
  ExpectSame(Pass(record), samples);
  ExpectSame(Pass(record), samples);
}

TEST(ImuRecord, StreamedKeepsTheHeadAndLearnsTheEndFromTheFirstPass) {
  const std::vector<ImuSample> source = Samples(3000, 1500);  // one gap of 3 intervals
  int opens = 0;
  const ImuRecord record = StreamedOver(&source, &opens);
  EXPECT_TRUE(record.streamed());
  EXPECT_EQ(opens, 0);  // nothing read before asked

  const std::vector<ImuSample>& head = record.Head(0.095);
  ASSERT_EQ(head.size(), 10u);  // up to and including the first sample at or after 0.095 s
  EXPECT_NEAR(head.back().t_s, 0.1, 1e-12);
  EXPECT_FALSE(record.end_known());
  EXPECT_EQ(record.known_end_s(), std::numeric_limits<double>::infinity());
  EXPECT_THROW(record.size(), std::logic_error);
  EXPECT_THROW(record.back(), std::logic_error);
  EXPECT_THROW(record.bridged_gaps(), std::logic_error);
  EXPECT_THROW(record.samples(), std::logic_error);

  // The first pass goes on from the head without opening the source again.
  const std::vector<ImuSample> first = Pass(record);
  EXPECT_EQ(opens, 1);
  ASSERT_EQ(first.size(), 3002u);  // the gap's sample split into 3
  EXPECT_TRUE(record.end_known());
  EXPECT_EQ(record.size(), 3002u);
  EXPECT_EQ(record.back().t_s, source.back().t_s);
  EXPECT_EQ(record.bridged_gaps(), 1u);
  for (const ImuSample& s : first) EXPECT_NEAR(s.dt_s, 0.01, 1e-12) << s.t_s;

  // Later passes read the source again and give the same samples.
  ExpectSame(Pass(record), first);
  EXPECT_EQ(opens, 2);

  // A head longer than the one kept reads the source again up to there.
  const std::vector<ImuSample>& longer = record.Head(0.495);
  EXPECT_EQ(opens, 3);
  ExpectSame(longer, std::vector<ImuSample>(first.begin(), first.begin() + 50));
}

TEST(ImuRecord, StreamedSameAsInMemory) {
  const std::vector<ImuSample> source = Samples(2500, 700);
  int opens = 0;
  const ImuRecord streamed = StreamedOver(&source, &opens);
  std::size_t bridged = 0;
  const std::unique_ptr<ImuReader> direct =
      GapBridgingImuReader(std::make_unique<VectorReader>(&source), 1.0, "max_bridge_gap_s", 0.0, &bridged);
  std::vector<ImuSample> all = ReadAll(*direct);
  const ImuRecord in_memory(std::move(all), bridged);
  ExpectSame(Pass(streamed), Pass(in_memory));
  EXPECT_EQ(streamed.size(), in_memory.size());
  EXPECT_EQ(streamed.bridged_gaps(), in_memory.bridged_gaps());
  EXPECT_EQ(streamed.bridged_gaps(), 1u);
}

TEST(ImuRecord, AHeadReachingTheEndKnowsTheEnd) {
  const std::vector<ImuSample> source = Samples(20);
  int opens = 0;
  const ImuRecord record = StreamedOver(&source, &opens);
  EXPECT_EQ(record.Head(100.0).size(), 20u);
  EXPECT_TRUE(record.end_known());
  EXPECT_EQ(record.size(), 20u);
  EXPECT_EQ(record.back().t_s, source.back().t_s);
}

TEST(ImuRecord, EmptyStreamedRecord) {
  const std::vector<ImuSample> source;
  int opens = 0;
  const ImuRecord record = StreamedOver(&source, &opens);
  EXPECT_TRUE(record.empty());
  EXPECT_THROW(record.front(), std::logic_error);
  EXPECT_TRUE(Pass(record).empty());
}

}  // namespace ins_imu_record_test
}  // namespace navtwin::ins
