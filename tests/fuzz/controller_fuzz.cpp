// The controller's message handling and sequence validation face whatever a
// host sends. The input is a session: records of [u16 LE header][bytes], the
// header's low 15 bits the record's length, its top bit "send raw"; other
// records are framed here (so their CRC is right and the fuzzer reaches the
// messages themselves). The session is served by a real ControllerServer and
// Controller on the in-memory chip and a virtual clock, up to the hang-up.
// Whatever came, serving must end without a crash, a hang or an exception,
// and with every LED dark and the trigger released.
#include "lightstage/common/framing.hpp"
#include "lightstage/common/link.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/firmware/controller.hpp"
#include "lightstage/firmware/controller_server.hpp"
#include "lightstage/firmware/dome_io.hpp"

#include "chunked_link.hpp"
#include "support/fake_chip.hpp"
#include "support/test_rigs.hpp"
#include "support/virtual_clock.hpp"

#include <google/protobuf/stubs/logging.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <span>
#include <string>
#include <vector>

namespace {

namespace fw = lightstage::firmware;
using Bytes = std::vector<std::uint8_t>;

void require(bool condition) {
  if (!condition) std::abort();
}

std::deque<Bytes> session_of(const std::uint8_t* data, std::size_t size) {
  std::deque<Bytes> chunks;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const unsigned header = data[at] | static_cast<unsigned>(data[at + 1]) << 8;
    at += 2;
    const std::size_t length = std::min<std::size_t>(header & 0x7fffu, size - at);
    const std::span<const std::uint8_t> bytes(data + at, length);
    at += length;
    if (header & 0x8000u) {
      chunks.emplace_back(bytes.begin(), bytes.end());
    } else {
      chunks.push_back(lightstage::protocol::encode_frame(bytes));
    }
  }
  return chunks;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Protobuf logs every string field that is not UTF-8; that is expected here.
  google::protobuf::SetLogHandler(nullptr);
  lightstage::set_log_level("off");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const lightstage::Rig rig = fw::testing::direct_rig();
  fw::testing::VirtualClock clock;
  auto chip = fw::testing::FakeChip::with_lines(16, clock);
  chip->set_camera({8, 9, 50'000, 2'000'000, false});
  {
    fw::Controller controller(rig, fw::open_dome_io(rig, *chip, clock), clock);
    fw::ControllerServer server(controller, {});
    const std::atomic<bool> stop{false};
    server.serve_client(std::make_unique<lightstage::fuzz::ChunkedLink>(session_of(data, size)), stop);
    require(!controller.active());
    require(controller.status().leds_on_size() == 0);
  }
  for (const int line : {0, 1, 2, 3, 8}) require(chip->value(static_cast<unsigned>(line)) == 0);
  return 0;
}
