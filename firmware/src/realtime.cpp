#include "lightstage/firmware/realtime.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <thread>

namespace lightstage::firmware {

RealtimeResult lock_memory() {
#if defined(__SANITIZE_ADDRESS__)
  return {false, "mlockall skipped: built with AddressSanitizer"};
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return {false, "mlockall skipped: built with AddressSanitizer"};
#endif
#endif
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    return {false, fmt::format("mlockall: {} (needs CAP_IPC_LOCK or a larger RLIMIT_MEMLOCK)",
                               std::strerror(errno))};
  }
  return {true, {}};
}

RealtimeResult make_this_thread_realtime(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error != 0) {
    return {false, fmt::format("SCHED_FIFO priority {}: {} (needs CAP_SYS_NICE or RLIMIT_RTPRIO)", priority,
                               std::strerror(error))};
  }
  return {true, {}};
}

RealtimeResult realtime_permitted(int priority) {
  RealtimeResult result;
  std::thread probe([&] { result = make_this_thread_realtime(priority); });
  probe.join();
  return result;
}

}  // namespace lightstage::firmware
