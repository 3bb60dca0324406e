#include "lightstage/station/operator_access.hpp"

#include <arpa/inet.h>

#include <fmt/format.h>

#include <random>

namespace lightstage::station {

OperatorAccess::OperatorAccess(AccessOptions options) : options_(std::move(options)) {}

void OperatorAccess::check_token(std::string_view presented) const {
  if (options_.token.empty()) return;
  // Compared in constant time: the answer's timing says nothing of the token.
  unsigned char difference = presented.size() == options_.token.size() ? 0 : 1;
  for (std::size_t i = 0; i < options_.token.size(); ++i) {
    const char c = i < presented.size() ? presented[i] : '\0';
    difference |= static_cast<unsigned char>(c ^ options_.token[i]);
  }
  if (difference != 0)
    throw Refused(
        401, presented.empty() ? "this station needs its token (printed when it started)" : "wrong token");
}

bool OperatorAccess::held(Clock::time_point now) const {
  return holder_ && now - last_seen_ < options_.lease;
}

Role OperatorAccess::touch(const std::string& client, Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  if (holder_ && *holder_ == client && held(now)) {
    last_seen_ = now;
    return Role::kOperator;
  }
  return Role::kViewer;
}

void OperatorAccess::take(const std::string& client, const std::string& name, Clock::time_point now) {
  if (client.empty()) throw Refused(400, "taking control needs a client id (header X-Lightstage-Client)");
  const std::lock_guard lock(mutex_);
  if (held(now) && *holder_ != client)
    throw Refused(409, fmt::format("{} controls the station; this page is read-only until they release it",
                                   holder_name_.empty() ? std::string("another operator") : holder_name_));
  holder_ = client;
  holder_name_ = name.empty() ? "an operator" : name;
  last_seen_ = now;
}

void OperatorAccess::release(const std::string& client) {
  const std::lock_guard lock(mutex_);
  if (holder_ && *holder_ == client) holder_.reset();
}

void OperatorAccess::require_operator(const std::string& client, Clock::time_point now) {
  if (touch(client, now) != Role::kOperator)
    throw Refused(403, "only the operator in control can do this: take control first");
}

std::string OperatorAccess::name_of(const std::string& client) {
  const std::lock_guard lock(mutex_);
  return holder_ && *holder_ == client ? holder_name_ : std::string();
}

bool OperatorAccess::lapsed(Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  if (!holder_ || held(now)) return false;
  holder_.reset();
  return true;
}

nlohmann::json OperatorAccess::to_json(const std::string& client, Clock::time_point now) {
  const Role role = touch(client, now);
  const std::lock_guard lock(mutex_);
  return {{"operator", held(now) ? nlohmann::json(holder_name_) : nlohmann::json(nullptr)},
          {"you", role == Role::kOperator ? "operator" : "viewer"},
          {"token_required", token_required()}};
}

std::string random_token() {
  std::random_device entropy;
  std::string token;
  for (int i = 0; i < 4; ++i) token += fmt::format("{:08x}", entropy());
  return token;
}

bool is_loopback_address(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  // An address, not a name that starts like one ("127.0.0.1.example.org").
  in_addr address{};
  return ::inet_pton(AF_INET, host.c_str(), &address) == 1 && (ntohl(address.s_addr) >> 24) == 127;
}

}  // namespace lightstage::station
