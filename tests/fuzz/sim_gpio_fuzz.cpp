// The sim's GPIO server faces whatever a client sends. The input is a list of
// messages, each a 2-byte little-endian length and that many payload bytes,
// sent as valid frames (so they reach the message handling, not only the CRC
// check), then any bytes left over sent raw; the server must answer and keep
// serving or close the connection, never crash or hang. Every input talks to
// a fresh chip of the default dome, so faults armed by one do not leak into the next.
#include "chunked_link.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/link.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/sim/gpio/gpio_service.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"

#include <google/protobuf/stubs/logging.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <vector>

namespace {

using Bytes = std::vector<std::uint8_t>;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);  // non-UTF-8 strings are expected here
  lightstage::set_log_level("off");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const lightstage::Rig rig = lightstage::load_rig(lightstage::default_rig_path());
  std::deque<Bytes> chunks;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::size_t length = data[at] | (static_cast<std::size_t>(data[at + 1]) << 8);
    if (at + 2 + length > size) break;
    chunks.push_back(
        lightstage::protocol::encode_frame(std::span<const std::uint8_t>(data + at + 2, length)));
    at += 2 + length;
  }
  if (at < size) chunks.emplace_back(data + at, data + size);

  auto chip = std::make_shared<lightstage::sim::gpio::VirtualChip>(
      lightstage::sim::gpio::layout_from_rig(rig), lightstage::sim::gpio::chip_options_for(rig));
  lightstage::sim::gpio::GpioService service(chip);
  std::stop_source stop;
  service.serve(std::make_unique<lightstage::fuzz::ChunkedLink>(std::move(chunks)), stop.get_token());
  return 0;
}
