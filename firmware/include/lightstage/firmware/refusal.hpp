#pragma once
// Why the controller refuses a request: the protocol's error code and a
// message naming the LED, step, limit or value.

#include "lightstage/proto/controller.pb.h"

#include <string>

namespace lightstage::firmware {

struct Refusal {
  proto::Error::Code code = proto::Error::BAD_REQUEST;
  std::string message;
};

}  // namespace lightstage::firmware
