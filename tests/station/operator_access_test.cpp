// Who may act at the station: the token, one operator at a time, the lease.
#include "lightstage/station/operator_access.hpp"

#include <gtest/gtest.h>

namespace lightstage::station {
namespace {

using std::chrono::seconds;

int refusal(const std::function<void()>& act) {
  try {
    act();
  } catch (const Refused& e) {
    return e.status();
  }
  return 0;
}

TEST(OperatorAccess, AMissingOrWrongTokenIsRefusedAndTheRightOnePasses) {
  const OperatorAccess access({"0123456789abcdef", seconds(15)});
  EXPECT_TRUE(access.token_required());
  EXPECT_EQ(refusal([&] { access.check_token(""); }), 401);
  EXPECT_EQ(refusal([&] { access.check_token("0123456789abcdeF"); }), 401);
  EXPECT_EQ(refusal([&] { access.check_token("0123456789abcdef0"); }), 401);
  EXPECT_EQ(refusal([&] { access.check_token("0123456789abcde"); }), 401);
  EXPECT_EQ(refusal([&] { access.check_token("0123456789abcdef"); }), 0);
  const OperatorAccess open({"", seconds(15)});
  EXPECT_EQ(refusal([&] { open.check_token(""); }), 0);
}

TEST(OperatorAccess, OneOperatorAtATimeTheOthersReadOnly) {
  OperatorAccess access({"", seconds(15)});
  const Clock::time_point t0 = Clock::now();
  access.take("tab-a", "Ann", t0);
  EXPECT_EQ(access.touch("tab-a", t0), Role::kOperator);
  EXPECT_EQ(access.touch("tab-b", t0), Role::kViewer);
  try {
    access.take("tab-b", "Bob", t0 + seconds(1));
    FAIL() << "a second operator took control";
  } catch (const Refused& e) {
    EXPECT_EQ(e.status(), 409);
    EXPECT_NE(std::string(e.what()).find("Ann"), std::string::npos) << e.what();
  }
  EXPECT_EQ(refusal([&] { access.require_operator("tab-b", t0); }), 403);
  EXPECT_EQ(access.to_json("tab-b", t0)["operator"], "Ann");
  EXPECT_EQ(access.to_json("tab-b", t0)["you"], "viewer");
  access.release("tab-b");  // not theirs to release
  EXPECT_EQ(access.touch("tab-a", t0), Role::kOperator);
  access.release("tab-a");
  access.take("tab-b", "Bob", t0 + seconds(2));
  EXPECT_EQ(access.name_of("tab-b"), "Bob");
  EXPECT_EQ(access.name_of("tab-a"), "");
  EXPECT_EQ(refusal([&] { access.take("", "nobody", t0); }), 400);
}

TEST(OperatorAccess, ControlLapsesWithoutRequestsAndIsTakenOver) {
  OperatorAccess access({"", seconds(15)});
  const Clock::time_point t0 = Clock::now();
  access.take("tab-a", "Ann", t0);
  // Every request of the operator renews the lease.
  EXPECT_EQ(access.touch("tab-a", t0 + seconds(10)), Role::kOperator);
  EXPECT_EQ(access.touch("tab-a", t0 + seconds(20)), Role::kOperator);
  EXPECT_FALSE(access.lapsed(t0 + seconds(30)));
  // A closed tab: no request for longer than the lease.
  EXPECT_TRUE(access.lapsed(t0 + seconds(36)));
  EXPECT_FALSE(access.lapsed(t0 + seconds(37))) << "a lapse is told once";
  EXPECT_EQ(access.touch("tab-a", t0 + seconds(37)), Role::kViewer);
  access.take("tab-b", "Bob", t0 + seconds(37));
  EXPECT_EQ(access.touch("tab-b", t0 + seconds(37)), Role::kOperator);
}

TEST(OperatorAccess, TokensAreRandomAndLoopbackIsKnown) {
  const std::string a = random_token(), b = random_token();
  EXPECT_EQ(a.size(), 32u);
  EXPECT_NE(a, b);
  EXPECT_TRUE(is_loopback_address("127.0.0.1"));
  EXPECT_TRUE(is_loopback_address("::1"));
  EXPECT_TRUE(is_loopback_address("localhost"));
  EXPECT_FALSE(is_loopback_address("0.0.0.0"));
  EXPECT_FALSE(is_loopback_address("192.168.1.20"));
  EXPECT_FALSE(is_loopback_address("::"));
  EXPECT_TRUE(is_loopback_address("127.1.2.3"));
  // Names that merely start like a loopback address resolve anywhere.
  EXPECT_FALSE(is_loopback_address("127.0.0.1.example.org"));
  EXPECT_FALSE(is_loopback_address("127.evil"));
}

}  // namespace
}  // namespace lightstage::station
