#include "numpy_arrays.hpp"

#include <opencv2/imgproc.hpp>

#include <cstring>
#include <string>
#include <vector>

namespace py = pybind11;

namespace lightstage::python {
namespace {

py::dtype dtype_of(int depth) {
  switch (depth) {
    case CV_8U:
      return py::dtype::of<std::uint8_t>();
    case CV_16U:
      return py::dtype::of<std::uint16_t>();
    case CV_32F:
      return py::dtype::of<float>();
    case CV_64F:
      return py::dtype::of<double>();
    default:
      throw py::type_error("unsupported image depth " + std::to_string(depth));
  }
}

}  // namespace

py::array to_numpy(const cv::Mat& image) {
  if (image.empty()) return py::array(py::dtype::of<float>(), std::vector<py::ssize_t>{0, 0});
  const cv::Mat dense = image.isContinuous() ? image : image.clone();
  std::vector<py::ssize_t> shape = {dense.rows, dense.cols};
  if (dense.channels() > 1) shape.push_back(dense.channels());
  py::array out(dtype_of(dense.depth()), shape);
  std::memcpy(out.mutable_data(), dense.data, dense.total() * dense.elemSize());
  return out;
}

py::array image_to_numpy(const cv::Mat& image) {
  if (image.channels() != 3) return to_numpy(image);
  cv::Mat rgb;
  cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
  return to_numpy(rgb);
}

py::array mask_to_numpy(const cv::Mat& mask) {
  py::array_t<bool> out({mask.rows, mask.cols});
  auto view = out.mutable_unchecked<2>();
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) view(y, x) = mask.at<std::uint8_t>(y, x) != 0;
  return out;
}

py::array_t<double> to_numpy(const Eigen::MatrixXd& matrix) {
  py::array_t<double> out({matrix.rows(), matrix.cols()});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r)
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) view(r, c) = matrix(r, c);
  return out;
}

cv::Mat float_mat(const py::array& array, int channels, const char* name) {
  const auto values = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw py::type_error(std::string(name) + ": expected a numeric array");
  const bool shape_ok =
      channels == 1 ? values.ndim() == 2 : values.ndim() == 3 && values.shape(2) == channels;
  if (!shape_ok)
    throw py::value_error(std::string(name) + ": expected shape (height, width" +
                          (channels == 1 ? std::string(")") : ", " + std::to_string(channels) + ")"));
  cv::Mat out(static_cast<int>(values.shape(0)), static_cast<int>(values.shape(1)), CV_32FC(channels));
  std::memcpy(out.data, values.data(), out.total() * out.elemSize());
  return out;
}

cv::Mat mask_mat(const py::array& array, const char* name) {
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values || values.ndim() != 2)
    throw py::value_error(std::string(name) + ": expected shape (height, width)");
  cv::Mat out(static_cast<int>(values.shape(0)), static_cast<int>(values.shape(1)), CV_8UC1);
  const double* data = values.data();
  for (int i = 0; i < static_cast<int>(out.total()); ++i) out.data[i] = data[i] != 0 ? 255 : 0;
  return out;
}

}  // namespace lightstage::python
