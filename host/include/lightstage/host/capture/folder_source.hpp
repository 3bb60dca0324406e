#pragma once
// folder:PATH — shots that a tethering program (or the simulated DSLR) writes
// into a folder, as a camera::ShotSource. The folder is polled rather than
// watched with inotify, which misses files written from another machine onto
// a network share. A file counts once its size and time have stayed the same
// for at least one poll interval (a tethering program may still be writing it); names starting
// with '.' or ending in .tmp/.part and files other than camera images
// (io/image_io.hpp's formats) are never reported. Files there before start()
// are never reported: a resumed capture does not take an earlier run's shots
// for its own.
//
// Options: folder:PATH?poll_ms=N (default 50).

#include "lightstage/common/shot_source.hpp"

#include <memory>

namespace lightstage {

// Throws InputError naming the URI for a PATH that is missing or not a folder,
// or a bad option.
std::unique_ptr<camera::ShotSource> open_folder_source(const camera::CameraUri& uri);

}  // namespace lightstage
