#include "fake_chip.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace lightstage::firmware::testing {
namespace {

class FakeOutputLines final : public gpio::OutputLines {
 public:
  FakeOutputLines(FakeChip& chip, std::vector<unsigned> offsets)
      : chip_(chip), offsets_(std::move(offsets)) {}
  ~FakeOutputLines() override { chip_.release(offsets_); }
  void set(std::span<const int> values, std::int64_t t_ns) override { chip_.apply(offsets_, values, t_ns); }
  std::size_t size() const override { return offsets_.size(); }

 private:
  FakeChip& chip_;
  std::vector<unsigned> offsets_;
};

class FakeEdgeInput final : public gpio::EdgeInput {
 public:
  FakeEdgeInput(FakeChip& chip, unsigned offset) : chip_(chip), offset_(offset) {}
  ~FakeEdgeInput() override { chip_.release({offset_}); }
  std::optional<gpio::EdgeEvent> wait_until(std::int64_t deadline_ns) override {
    return chip_.next_edge(offset_, deadline_ns);
  }
  void drain() override { chip_.drain(offset_); }

 private:
  FakeChip& chip_;
  unsigned offset_;
};

}  // namespace

FakeChip::FakeChip(std::vector<std::string> names, Clock& clock, std::string label)
    : clock_(clock),
      label_(std::move(label)),
      names_(std::move(names)),
      consumers_(names_.size()),
      values_(names_.size(), 0),
      active_low_(names_.size(), false) {}

std::unique_ptr<FakeChip> FakeChip::with_lines(unsigned count, Clock& clock,
                                               const std::map<unsigned, std::string>& named) {
  std::vector<std::string> names(count);
  for (const auto& [offset, name] : named) names.at(offset) = name;
  return std::make_unique<FakeChip>(std::move(names), clock);
}

gpio::ChipInfo FakeChip::info() const {
  const std::lock_guard lock(mutex_);
  return {label_, names_, consumers_};
}

void FakeChip::claim(unsigned offset, bool low, const std::string& consumer) {
  if (offset >= names_.size()) throw gpio::GpioError(fmt::format("{}: no line {}", label_, offset));
  if (!consumers_[offset].empty()) {
    throw gpio::GpioError(
        fmt::format("{}: line {} is busy, used by \"{}\"", label_, offset, consumers_[offset]));
  }
  consumers_[offset] = consumer;
  active_low_[offset] = low;
}

std::unique_ptr<gpio::OutputLines> FakeChip::request_outputs(std::span<const unsigned> offsets,
                                                             std::span<const bool> active_low,
                                                             std::span<const int> initial,
                                                             const std::string& consumer) {
  const std::lock_guard lock(mutex_);
  const std::vector<std::string> before = consumers_;
  try {
    for (std::size_t i = 0; i < offsets.size(); ++i)
      claim(offsets[i], !active_low.empty() && active_low[i], consumer);
  } catch (const gpio::GpioError&) {
    consumers_ = before;  // all or nothing, like a kernel line request
    throw;
  }
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    values_[offsets[i]] = !initial.empty() && initial[i] ? 1 : 0;
  }
  return std::make_unique<FakeOutputLines>(*this, std::vector<unsigned>(offsets.begin(), offsets.end()));
}

std::unique_ptr<gpio::EdgeInput> FakeChip::request_edges(unsigned offset, bool active_low,
                                                         const std::string& consumer) {
  const std::lock_guard lock(mutex_);
  claim(offset, active_low, consumer);
  return std::make_unique<FakeEdgeInput>(*this, offset);
}

void FakeChip::set_camera(const FakeCamera& camera) {
  const std::lock_guard lock(mutex_);
  camera_ = camera;
}

void FakeChip::occupy(unsigned offset, const std::string& consumer) {
  const std::lock_guard lock(mutex_);
  consumers_.at(offset) = consumer;
}

void FakeChip::fail_after_sets(int n) {
  const std::lock_guard lock(mutex_);
  sets_left_ = n;
}

void FakeChip::apply(const std::vector<unsigned>& offsets, std::span<const int> values, std::int64_t t_ns) {
  const std::lock_guard lock(mutex_);
  if (values.size() != offsets.size()) throw gpio::GpioError("fake chip: wrong number of values");
  if (sets_left_ == 0) throw gpio::GpioError("fake chip: injected failure");
  if (sets_left_ > 0) --sets_left_;
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const unsigned offset = offsets[i];
    const int value = values[i] ? 1 : 0;
    if (values_[offset] == value) continue;
    values_[offset] = value;
    changes_.push_back({t_ns, offset, value});
    if (camera_ && !camera_->lost && offset == camera_->trigger && value == 1) {
      auto& queue = edges_[camera_->strobe];
      queue.push_back({camera_->strobe, true, t_ns + camera_->delay_ns});
      queue.push_back({camera_->strobe, false, t_ns + camera_->delay_ns + camera_->exposure_ns});
    }
  }
}

void FakeChip::release(const std::vector<unsigned>& offsets) {
  const std::lock_guard lock(mutex_);
  for (const unsigned offset : offsets) consumers_[offset].clear();
}

std::optional<gpio::EdgeEvent> FakeChip::next_edge(unsigned offset, std::int64_t deadline_ns) {
  std::optional<gpio::EdgeEvent> edge;
  {
    const std::lock_guard lock(mutex_);
    auto& queue = edges_[offset];
    if (!queue.empty() && (queue.front().t_ns <= deadline_ns || queue.front().t_ns <= clock_.now_ns())) {
      edge = queue.front();
      queue.pop_front();
    }
  }
  clock_.sleep_until(edge ? edge->t_ns : deadline_ns);
  return edge;
}

void FakeChip::drain(unsigned offset) {
  const std::lock_guard lock(mutex_);
  auto& queue = edges_[offset];
  const std::int64_t now = clock_.now_ns();
  while (!queue.empty() && queue.front().t_ns <= now) queue.pop_front();
}

std::vector<LineChange> FakeChip::changes() const {
  const std::lock_guard lock(mutex_);
  return changes_;
}

std::vector<LineChange> FakeChip::changes_of(unsigned offset) const {
  const std::lock_guard lock(mutex_);
  std::vector<LineChange> out;
  for (const auto& change : changes_) {
    if (change.offset == offset) out.push_back(change);
  }
  return out;
}

int FakeChip::value(unsigned offset) const {
  const std::lock_guard lock(mutex_);
  return values_.at(offset);
}

bool FakeChip::active_low(unsigned offset) const {
  const std::lock_guard lock(mutex_);
  return active_low_.at(offset);
}

std::string FakeChip::consumer(unsigned offset) const {
  const std::lock_guard lock(mutex_);
  return consumers_.at(offset);
}

}  // namespace lightstage::firmware::testing
