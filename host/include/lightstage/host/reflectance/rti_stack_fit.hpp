#pragma once
// PTM / HSH fits of a whole stack, per colour channel, on linear values:
//   value = (raw − black_level) / full_scale / light_intensity   (per channel)
// as radiometry.hpp defines them (without its grey conversion or clamp), so
// an exported RTI relights in the stack's own units. Grey stacks fill all
// three channels alike.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/io/rti_files.hpp"

namespace lightstage {

// Throws InputError for an empty stack, frames of different size, or fewer
// frames than the basis has terms.
io::RtiImage fit_rti_stack(const ImageStack& stack, RtiBasis basis);

// Per channel, the frame as linear float values (CV_32FC1 each, r, g, b).
std::array<cv::Mat, 3> linear_channels(const Frame& frame);

}  // namespace lightstage
