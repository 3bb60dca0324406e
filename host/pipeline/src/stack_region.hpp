#pragma once
// A region of a stack read without decoding more than its rows (--crop):
// the rows from io::StackBands, cut to the region's columns.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/io/stack_bands.hpp"

#include <opencv2/core.hpp>

namespace lightstage::pipeline {

// `area` of every image of `stack` (frames, dark frames, mask, ground truth)
// as views of their pixels; frames that share a dark frame still share it.
ImageStack stack_area(const ImageStack& stack, const cv::Rect& area);

// Rows [y0, y0 + rows) of `stack` cut to the columns of `region`: frames, dark
// frames (shared between frames as the stack shares them), mask and ground truth.
ImageStack read_region_rows(io::StackBands& stack, const cv::Rect& region, int y0, int rows);

}  // namespace lightstage::pipeline
