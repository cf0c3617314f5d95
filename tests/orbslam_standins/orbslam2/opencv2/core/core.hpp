#pragma once
// Stand-in for OpenCV's cv::Mat as ORB-SLAM2 uses it for poses (4x4) and positions (3x1): dense
// CV_32F matrices read with at<float>(row, col) and at<float>(i). Enough for the exporter's test;
// not OpenCV.

#include <cstddef>
#include <memory>
#include <vector>

#define CV_32F 5

namespace cv {

class Mat {
 public:
  Mat() = default;
  Mat(int rows_, int cols_, int /*type: CV_32F only*/)
      : rows(rows_),
        cols(cols_),
        data_(std::make_shared<std::vector<float>>(rows_ * cols_, 0.0f)) {}

  template <class T>
  T& at(int r, int c) {
    return (*data_)[static_cast<std::size_t>(r * cols + c)];
  }
  template <class T>
  const T& at(int r, int c) const {
    return (*data_)[static_cast<std::size_t>(r * cols + c)];
  }
  template <class T>
  T& at(int i) {
    return (*data_)[static_cast<std::size_t>(i)];
  }
  template <class T>
  const T& at(int i) const {
    return (*data_)[static_cast<std::size_t>(i)];
  }
  /// A deep copy (cv::Mat copies share their data, as here).
  Mat clone() const {
    Mat m(rows, cols, CV_32F);
    *m.data_ = *data_;
    return m;
  }
  bool empty() const { return !data_ || data_->empty(); }

  int rows = 0, cols = 0;

 private:
  std::shared_ptr<std::vector<float>> data_;
};

}  // namespace cv
