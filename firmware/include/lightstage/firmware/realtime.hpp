#pragma once
// Real-time scheduling for the sequencer: SCHED_FIFO keeps other processes
// from delaying a deadline wake-up, mlockall keeps page faults out of the
// timing path. Both need privileges (CAP_SYS_NICE / RLIMIT_RTPRIO,
// CAP_IPC_LOCK / RLIMIT_MEMLOCK); without them the daemon runs with a
// warning and reports realtime=false in its Capabilities.

#include <string>

namespace lightstage::firmware {

struct RealtimeResult {
  bool ok = false;
  std::string problem;  // why not, when !ok
};

// Locks current and future pages in memory (process-wide). Skipped under
// AddressSanitizer, whose shadow memory cannot be locked.
RealtimeResult lock_memory();

// Switches the calling thread to SCHED_FIFO at `priority` (1..99).
RealtimeResult make_this_thread_realtime(int priority);

// Whether a thread of this process may switch to SCHED_FIFO at `priority`
// (tried on a short-lived thread).
RealtimeResult realtime_permitted(int priority);

}  // namespace lightstage::firmware
