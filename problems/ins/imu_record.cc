#include "problems/ins/imu_record.h"

#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace navtwin::ins {

/// A streamed record's shared state: the head read so far, the reader positioned after it
/// (null once a pass has taken it), and what a pass that reached the end found.
struct ImuRecord::Stream {
  Opener open;
  std::vector<ImuSample> head;
  std::unique_ptr<ImuReader> reader;
  std::size_t reader_bridged = 0;  ///< gaps `reader` has bridged so far
  bool end_known = false;
  std::size_t count = 0;
  ImuSample last;
  std::size_t bridged = 0;

  void EndReached(std::size_t n, const ImuSample& last_sample, std::size_t bridged_gaps) {
    end_known = true;
    count = n;
    last = last_sample;
    bridged = bridged_gaps;
  }
};

/// One pass over a record: the samples in memory, or a streamed record's head replayed and
/// its reader read on (the first pass) or its file read again. Records what it finds at
/// the end.
class ImuRecord::PassReader final : public ImuReader {
 public:
  explicit PassReader(const std::vector<ImuSample>* samples) : samples_(samples), replay_(samples->size()) {}

  explicit PassReader(std::shared_ptr<Stream> stream) : stream_(std::move(stream)) {
    if (stream_->reader) {
      samples_ = &stream_->head;
      replay_ = stream_->head.size();
      reader_ = std::move(stream_->reader);
      bridged_ = &stream_->reader_bridged;
    } else {
      reader_ = stream_->open(&own_bridged_);
      bridged_ = &own_bridged_;
    }
  }

  bool Next(ImuSample* sample) override {
    if (next_ < replay_) {
      *sample = (*samples_)[next_++];
      ++count_;
      last_ = *sample;
      return true;
    }
    if (!reader_ || !reader_->Next(sample)) {
      if (stream_ && count_ > 0 && !stream_->end_known) {
        stream_->EndReached(count_, last_, *bridged_);
      }
      return false;
    }
    ++count_;
    last_ = *sample;
    return true;
  }

  const std::string& path() const override {
    static const std::string kInMemory = "(IMU samples in memory)";
    return reader_ ? reader_->path() : kInMemory;
  }

 private:
  const std::vector<ImuSample>* samples_ = nullptr;
  std::size_t replay_ = 0;
  std::size_t next_ = 0;
  std::shared_ptr<Stream> stream_;
  std::unique_ptr<ImuReader> reader_;
  std::size_t own_bridged_ = 0;
  std::size_t* bridged_ = nullptr;
  std::size_t count_ = 0;
  ImuSample last_;
};

ImuRecord::ImuRecord() = default;

ImuRecord::ImuRecord(std::vector<ImuSample> samples, std::size_t bridged_gaps)
    : samples_(std::move(samples)), bridged_gaps_(bridged_gaps) {}

ImuRecord ImuRecord::Streamed(Opener open) {
  ImuRecord r;
  r.stream_ = std::make_shared<Stream>();
  r.stream_->open = std::move(open);
  return r;
}

bool ImuRecord::streamed() const { return stream_ != nullptr; }

const std::vector<ImuSample>& ImuRecord::Head(double t_s) const {
  if (!stream_) return samples_;
  Stream& st = *stream_;
  while (!(st.end_known && st.head.size() == st.count) && (st.head.empty() || st.head.back().t_s < t_s)) {
    if (!st.reader) {
      // A pass took the reader: read the file again up to where the head ends.
      st.reader_bridged = 0;
      st.reader = st.open(&st.reader_bridged);
      ImuSample skipped;
      for (std::size_t k = 0; k < st.head.size(); ++k) {
        if (!st.reader->Next(&skipped)) throw std::runtime_error(st.reader->path() + ": the IMU file became shorter");
      }
    }
    ImuSample s;
    if (!st.reader->Next(&s)) {
      if (!st.head.empty()) st.EndReached(st.head.size(), st.head.back(), st.reader_bridged);
      break;
    }
    st.head.push_back(s);
  }
  return st.head;
}

std::unique_ptr<ImuReader> ImuRecord::Read() const {
  if (!stream_) return std::make_unique<PassReader>(&samples_);
  return std::make_unique<PassReader>(stream_);
}

bool ImuRecord::empty() const { return Head(-std::numeric_limits<double>::infinity()).empty(); }

const ImuSample& ImuRecord::front() const {
  const std::vector<ImuSample>& head = Head(-std::numeric_limits<double>::infinity());
  if (head.empty()) throw std::logic_error("ImuRecord::front: the record is empty");
  return head.front();
}

double ImuRecord::begin_s() const { return front().t_s - front().dt_s; }

bool ImuRecord::end_known() const { return !stream_ || stream_->end_known; }

double ImuRecord::known_end_s() const {
  return end_known() ? back().t_s : std::numeric_limits<double>::infinity();
}

const ImuSample& ImuRecord::back() const {
  if (!stream_) {
    if (samples_.empty()) throw std::logic_error("ImuRecord::back: the record is empty");
    return samples_.back();
  }
  if (!stream_->end_known) throw std::logic_error("ImuRecord::back: no pass has reached the end of the stream yet");
  return stream_->last;
}

std::size_t ImuRecord::size() const {
  if (!stream_) return samples_.size();
  if (!stream_->end_known) throw std::logic_error("ImuRecord::size: no pass has reached the end of the stream yet");
  return stream_->count;
}

std::size_t ImuRecord::bridged_gaps() const {
  if (!stream_) return bridged_gaps_;
  if (!stream_->end_known) {
    throw std::logic_error("ImuRecord::bridged_gaps: no pass has reached the end of the stream yet");
  }
  return stream_->bridged;
}

const std::vector<ImuSample>& ImuRecord::samples() const {
  if (stream_) throw std::logic_error("ImuRecord::samples: the record is streamed, not in memory");
  return samples_;
}

void ImuRecord::push_back(const ImuSample& s) {
  if (stream_) throw std::logic_error("ImuRecord::push_back: the record is streamed");
  samples_.push_back(s);
}

}  // namespace navtwin::ins
