// WriteQueue: order across batches, the thread the rows are written on, back-pressure,
// the sink's exception reaching the producer, destruction without Finish.
#include "core/io/write_queue.h"

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace navtwin {
namespace write_queue_test {

TEST(WriteQueue, RowsArriveInOrderOnOneOtherThread) {
  std::vector<int> written;
  std::vector<std::thread::id> threads;
  {
    WriteQueue<int> queue(
        [&](const std::vector<int>& rows) {
          threads.push_back(std::this_thread::get_id());
          written.insert(written.end(), rows.begin(), rows.end());
        },
        /*batch_rows=*/7, /*depth=*/2);
    for (int i = 0; i < 1000; ++i) queue.Push(i);
    queue.Finish();
  }
  ASSERT_EQ(written.size(), 1000u);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(written[i], i);
  // 1000 rows in batches of 7: 142 full batches and the rest (6 rows) at Finish.
  EXPECT_EQ(threads.size(), 143u);
  for (const auto& id : threads) {
    EXPECT_EQ(id, threads.front());
    EXPECT_NE(id, std::this_thread::get_id());
  }
}

TEST(WriteQueue, FewerRowsThanABatchAreWrittenByFinishOnTheCallersThread) {
  std::vector<int> written;
  std::thread::id writer;
  WriteQueue<int> queue(
      [&](const std::vector<int>& rows) {
        writer = std::this_thread::get_id();
        written = rows;
      },
      100, 2);
  queue.Push(1);
  queue.Push(2);
  EXPECT_TRUE(written.empty());  // nothing before Finish
  queue.Finish();
  EXPECT_EQ(written, (std::vector<int>{1, 2}));
  EXPECT_EQ(writer, std::this_thread::get_id());
  EXPECT_THROW(queue.Push(3), std::logic_error);
}

TEST(WriteQueue, ASlowSinkHoldsTheProducerToDepthBatches) {
  constexpr int kBatch = 10, kDepth = 2;
  std::atomic<int> pushed{0}, written{0}, largest_lead{0};
  WriteQueue<int> queue(
      [&](const std::vector<int>& rows) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        written += static_cast<int>(rows.size());
      },
      kBatch, kDepth);
  for (int i = 0; i < 400; ++i) {
    queue.Push(i);
    ++pushed;
    largest_lead = std::max(largest_lead.load(), pushed - written);
  }
  queue.Finish();
  EXPECT_EQ(written, 400);
  // At most: the batch being written, `depth` waiting, and the producer's own batch.
  EXPECT_LE(largest_lead, (kDepth + 2) * kBatch);
  EXPECT_GT(largest_lead, kBatch);  // the writer did lag: the bound above was exercised
}

TEST(WriteQueue, TheSinksExceptionReachesTheProducer) {
  int batches = 0;
  WriteQueue<int> queue(
      [&](const std::vector<int>&) {
        if (++batches == 3) throw std::runtime_error("disk full");
      },
      5, 1);
  bool thrown = false;
  try {
    for (int i = 0; i < 10000; ++i) queue.Push(i);
    queue.Finish();
  } catch (const std::runtime_error& e) {
    thrown = true;
    EXPECT_STREQ(e.what(), "disk full");
  }
  EXPECT_TRUE(thrown);
  EXPECT_EQ(batches, 3);  // nothing written after the failure
}

TEST(WriteQueue, DestroyedWithoutFinishStopsAndWritesAPrefix) {
  std::vector<int> written;
  {
    WriteQueue<int> queue([&](const std::vector<int>& rows) { written.insert(written.end(), rows.begin(), rows.end()); },
                          4, 3);
    for (int i = 0; i < 103; ++i) queue.Push(i);
  }  // no Finish: the thread ends, the rows not yet written are dropped
  EXPECT_LE(written.size(), 100u);  // never the 3 rows of the unfinished batch
  for (std::size_t i = 0; i < written.size(); ++i) ASSERT_EQ(written[i], static_cast<int>(i));
}

}  // namespace write_queue_test
}  // namespace navtwin
