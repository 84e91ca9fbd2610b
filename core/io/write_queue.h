// Hands rows to a writer thread in batches, so that a producer (an estimator at every IMU
// epoch) does not wait for number formatting and the disk.
//
// The rows reach `sink` in the order they were pushed, a batch at a time, always on one
// thread: the writer thread, started when the first batch is full, or the caller's thread
// in Finish() when fewer rows than a batch were pushed in all. At most `depth` full batches
// wait; a producer faster than the disk then blocks, so memory stays bounded
// (batch_rows * depth rows). An exception thrown by the sink stops the writing; the next
// Push() or Finish() rethrows it on the producer's thread. A queue destroyed without
// Finish() (the run failed) stops its thread and drops the rows not yet written.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

namespace navtwin {

template <class Row>
class WriteQueue {
 public:
  using Batch = std::vector<Row>;
  using Sink = std::function<void(const Batch&)>;

  explicit WriteQueue(Sink sink, std::size_t batch_rows = 256, std::size_t depth = 4)
      : sink_(std::move(sink)), batch_rows_(batch_rows < 1 ? 1 : batch_rows), depth_(depth < 1 ? 1 : depth) {
    filling_.reserve(batch_rows_);
  }
  ~WriteQueue() { Stop(); }
  WriteQueue(const WriteQueue&) = delete;
  WriteQueue& operator=(const WriteQueue&) = delete;

  /// Appends a row; hands the batch to the writer when it is full (blocking while `depth`
  /// batches wait). Rethrows the sink's exception, if it threw.
  void Push(Row row) {
    if (finished_) throw std::logic_error("WriteQueue: Push after Finish");
    filling_.push_back(std::move(row));
    if (filling_.size() == batch_rows_) Hand();
  }

  /// Writes every row pushed and waits for it; rethrows the sink's exception, if it threw.
  /// The queue takes no rows after it.
  void Finish() {
    if (finished_) return;
    finished_ = true;
    if (!worker_.joinable()) {
      if (!filling_.empty()) sink_(filling_);
      Batch().swap(filling_);
      return;
    }
    if (!filling_.empty()) Hand();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    ready_.notify_one();
    worker_.join();
    spare_.clear();  // the queue's memory goes now, not when its owner does
    Batch().swap(filling_);
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Hand() {
    if (!worker_.joinable()) worker_ = std::thread([this] { Work(); });
    Batch next;
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [this] { return waiting_.size() < depth_ || error_; });
    if (error_) std::rethrow_exception(error_);
    waiting_.push_back(std::move(filling_));
    if (!spare_.empty()) {
      next = std::move(spare_.back());
      spare_.pop_back();
    }
    lock.unlock();
    ready_.notify_one();
    filling_ = std::move(next);
    filling_.clear();
    filling_.reserve(batch_rows_);
  }

  void Work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ready_.wait(lock, [this] { return !waiting_.empty() || closing_ || stopping_; });
      if (stopping_ || waiting_.empty()) return;
      Batch batch = std::move(waiting_.front());
      waiting_.pop_front();
      lock.unlock();
      try {
        sink_(batch);
      } catch (...) {
        lock.lock();
        error_ = std::current_exception();
        waiting_.clear();
        room_.notify_all();
        return;
      }
      batch.clear();
      lock.lock();
      spare_.push_back(std::move(batch));
      room_.notify_one();
    }
  }

  void Stop() {
    if (!worker_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    ready_.notify_one();
    worker_.join();
  }

  Sink sink_;
  std::size_t batch_rows_;
  std::size_t depth_;
  Batch filling_;  ///< the producer's batch (only the producer touches it)
  bool finished_ = false;

  std::mutex mutex_;  ///< guards what follows
  std::condition_variable ready_;  ///< a batch waits, or the queue closes or stops
  std::condition_variable room_;   ///< a batch was taken, or the sink failed
  std::deque<Batch> waiting_;
  std::vector<Batch> spare_;  ///< written batches, their storage reused
  std::exception_ptr error_;
  bool closing_ = false;   ///< Finish(): write what waits, then end
  bool stopping_ = false;  ///< destruction: end now
  std::thread worker_;     ///< last: started after the members it uses
};

}  // namespace navtwin
