// The station's request bodies come from any browser or script on the
// network: every reader must give a request or a Refused (400), never a crash
// and never another exception (a JSON type error would be a 500).
#include "lightstage/station/operator_access.hpp"
#include "lightstage/station/station_requests.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

namespace {

template <typename Read>
void read_or_refuse(Read read, const nlohmann::json& body) {
  try {
    (void)read(body);
  } catch (const lightstage::station::Refused& e) {
    if (e.status() != 400) __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lightstage::station;
  const std::string text(reinterpret_cast<const char*>(data), size);
  const nlohmann::json body = nlohmann::json::parse(text, nullptr, false);
  if (body.is_discarded()) return 0;
  read_or_refuse(leds_request, body);
  read_or_refuse(preview_request, body);
  read_or_refuse(capture_request, body);
  read_or_refuse(calibration_request, body);
  read_or_refuse(sphere_request, body);
  read_or_refuse(solve_request, body);
  // What a capture keeps for its resume reads back as itself.
  try {
    const CaptureRequest request = capture_request(body);
    if (capture_request(request.to_json()).to_json() != request.to_json()) __builtin_trap();
  } catch (const Refused&) {
  }
  return 0;
}
