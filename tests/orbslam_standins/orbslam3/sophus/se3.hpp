#pragma once
// Stand-in for Sophus::SE3f as ORB-SLAM3 (1.0) uses it for keyframe poses: a rotation and a
// translation, rotationMatrix(), translation(), inverse(). Not Sophus.

#include <Eigen/Core>

namespace Sophus {

template <class Scalar>
class SE3 {
 public:
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;

  SE3() : R_(Matrix3::Identity()), t_(Vector3::Zero()) {}
  SE3(const Matrix3& R, const Vector3& t) : R_(R), t_(t) {}

  Matrix3 rotationMatrix() const { return R_; }
  const Vector3& translation() const { return t_; }
  SE3 inverse() const { return SE3(R_.transpose(), -(R_.transpose() * t_)); }
  Vector3 operator*(const Vector3& p) const { return R_ * p + t_; }

 private:
  Matrix3 R_;
  Vector3 t_;
};

using SE3f = SE3<float>;

}  // namespace Sophus
