#pragma once
// Who may do what at the station: one controlling operator at a time, every
// other client read-only; a token for any listen address but loopback.
//
// A client is a browser tab (an id it makes up and sends with each request).
// Control is a lease renewed by every request of its holder: a closed tab
// lets it lapse, so the dome is never held by someone who left.

#include "lightstage/common/error.hpp"

#include <chrono>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace lightstage::station {

using Clock = std::chrono::steady_clock;

enum class Role { kViewer, kOperator };

// A request the station refuses: the HTTP status and a message naming why.
class Refused : public Error {
 public:
  Refused(int status, const std::string& message) : Error(message), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

struct AccessOptions {
  std::string token;  // empty = none asked (loopback only)
  std::chrono::milliseconds lease{std::chrono::seconds(15)};
};

class OperatorAccess {
 public:
  explicit OperatorAccess(AccessOptions options);

  bool token_required() const { return !options_.token.empty(); }
  // Throws Refused(401) when a token is required and `presented` is not it.
  void check_token(std::string_view presented) const;

  // The client's role now; a request from the operator renews the lease.
  Role touch(const std::string& client, Clock::time_point now);
  // Takes control for `client` (shown to others as `name`): when free, when
  // the holder's lease lapsed, or when `client` holds it already. Throws
  // Refused(409) naming the operator who has it.
  void take(const std::string& client, const std::string& name, Clock::time_point now);
  void release(const std::string& client);
  // Throws Refused(403) unless `client` controls the station.
  void require_operator(const std::string& client, Clock::time_point now);
  // The name `client` took control under; "" when it does not hold control.
  std::string name_of(const std::string& client);
  // True once, when a lease lapsed since the last call (the station then darkens what was lit by hand).
  bool lapsed(Clock::time_point now);

  // {"operator": name or null, "you": "operator" | "viewer", "token_required": bool}
  nlohmann::json to_json(const std::string& client, Clock::time_point now);

 private:
  bool held(Clock::time_point now) const;

  AccessOptions options_;
  std::mutex mutex_;
  std::optional<std::string> holder_;
  std::string holder_name_;
  Clock::time_point last_seen_{};
};

// 128 random bits as 32 hex digits, from the system's entropy source.
std::string random_token();

// Is `host` (an address to listen on) reachable only from this machine?
bool is_loopback_address(const std::string& host);

}  // namespace lightstage::station
