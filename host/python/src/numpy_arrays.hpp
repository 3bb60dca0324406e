#pragma once
// cv::Mat and Eigen matrices to and from numpy arrays, always by copy (the
// arrays outlive the C++ objects). Colour images come out in RGB order (OpenCV
// holds BGR); normals keep their (x, y, z) channel order.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace lightstage::python {

// H×W or H×W×C array of the Mat's element type (8/16-bit unsigned, 32-bit float).
pybind11::array to_numpy(const cv::Mat& image);
// Same, with three-channel BGR images turned to RGB.
pybind11::array image_to_numpy(const cv::Mat& image);
// A CV_8UC1 mask as H×W bool.
pybind11::array mask_to_numpy(const cv::Mat& mask);
pybind11::array_t<double> to_numpy(const Eigen::MatrixXd& matrix);

// A float32 H×W×C (or H×W) array as CV_32FC(C); `name` is the argument in errors.
cv::Mat float_mat(const pybind11::array& array, int channels, const char* name);
// An H×W array of bools or numbers (non-zero = inside) as CV_8UC1 255/0.
cv::Mat mask_mat(const pybind11::array& array, const char* name);

}  // namespace lightstage::python
