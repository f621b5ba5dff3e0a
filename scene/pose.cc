#include "scene/pose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace p2i::scene {

namespace {

bool AllFinite(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  return t.allFinite() && q.coeffs().allFinite();
}

}  // namespace

Pose::Pose() : t_(Eigen::Vector3d::Zero()), q_(Eigen::Quaterniond::Identity()) {}

Pose::Pose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation)
    : t_(translation), q_(rotation) {
  if (!AllFinite(t_, q_)) throw std::invalid_argument("Pose: non-finite translation or rotation");
  const double n = q_.norm();
  if (!(n > 1e-12)) throw std::invalid_argument("Pose: quaternion has zero norm");
  q_.coeffs() /= n;
  Canonicalize();
}

void Pose::Canonicalize() {
  if (q_.w() < 0.0) q_.coeffs() = -q_.coeffs();
}

Pose Pose::FromMatrix(const Eigen::Matrix4d& m) {
  if (!m.allFinite()) throw std::invalid_argument("Pose::FromMatrix: non-finite values");
  const Eigen::RowVector4d last = m.row(3);
  if ((last - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) {
    throw std::invalid_argument("Pose::FromMatrix: last row must be 0 0 0 1");
  }
  // Project the rotation block onto SO(3) (datasets store slightly non-orthonormal matrices).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.block<3, 3>(0, 0),
                                        Eigen::ComputeFullU | Eigen::ComputeFullV);
  // ... but only slightly: a zero, scaled or sheared block is no rotation (7-Scenes files are
  // orthonormal to ~1e-4; 1e-2 leaves room for any real dataset).
  const Eigen::Vector3d sv = svd.singularValues();
  if ((sv - Eigen::Vector3d::Ones()).cwiseAbs().maxCoeff() > 1e-2) {
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "Pose::FromMatrix: the rotation block is not a rotation (singular values %.4g "
                  "%.4g %.4g, must be 1 within 0.01: a zero or scaled block?)",
                  sv(0), sv(1), sv(2));
    throw std::invalid_argument(buf);
  }
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) {
    throw std::invalid_argument("Pose::FromMatrix: rotation block is a reflection");
  }
  return Pose(m.block<3, 1>(0, 3), Eigen::Quaterniond(r));
}

Pose Pose::FromVector7(const Vector7d& v) {
  return Pose(v.head<3>(), Eigen::Quaterniond(v(6), v(3), v(4), v(5)));
}

namespace {
// |norm - 1| allowed for quaternions read from files: the wire's tolerance
// (msgs::kQuaternionTolerance), so files and messages agree.
constexpr double kQuaternionNormTolerance = 1e-3;
}  // namespace

Pose Pose::FromTumLine(const std::string& line, double* stamp) {
  static const char* const kFields[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  std::istringstream in(line);
  double f[8];
  std::string word;
  for (int i = 0; i < 8; ++i) {
    if (!(in >> word)) {
      throw std::invalid_argument(i == 0 ? "TUM line has no timestamp: '" + line + "'"
                                         : "TUM line needs 'timestamp tx ty tz qx qy qz qw', got: '" +
                                               line + "'");
    }
    char* end = nullptr;
    f[i] = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') {
      throw std::invalid_argument(std::string("TUM line: ") + kFields[i] + " '" + word +
                                  "' is not a number");
    }
    if (!std::isfinite(f[i])) {
      throw std::invalid_argument(std::string("TUM line: ") + kFields[i] + " is " +
                                  (std::isnan(f[i]) ? "NaN" : "infinite") + " ('" + word + "')");
    }
  }
  if (in >> word) throw std::invalid_argument("TUM line has extra fields: '" + line + "'");
  const double norm = std::sqrt(f[4] * f[4] + f[5] * f[5] + f[6] * f[6] + f[7] * f[7]);
  // The same tolerance as the wire (msgs decoder, synthesizer): files agree with messages.
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    char buf[160];
    std::snprintf(buf, sizeof(buf),
                  "TUM line: quaternion (qx qy qz qw) has norm %.6g; it must be 1 within %g "
                  "(write unit quaternions)",
                  norm, kQuaternionNormTolerance);
    throw std::invalid_argument(buf);
  }
  if (stamp != nullptr) *stamp = f[0];
  Vector7d v;
  for (int i = 0; i < 7; ++i) v(i) = f[i + 1];
  return FromVector7(v);
}

Eigen::Matrix4d Pose::ToMatrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0) = q_.toRotationMatrix();
  m.block<3, 1>(0, 3) = t_;
  return m;
}

Vector7d Pose::ToVector7() const {
  Vector7d v;
  v << t_.x(), t_.y(), t_.z(), q_.x(), q_.y(), q_.z(), q_.w();
  return v;
}

std::string Pose::ToTumLine(double stamp) const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g", stamp, t_.x(),
                t_.y(), t_.z(), q_.x(), q_.y(), q_.z(), q_.w());
  return buf;
}

Pose Pose::operator*(const Pose& other) const {
  return Pose(q_ * other.t_ + t_, q_ * other.q_);
}

Pose Pose::Inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return Pose(-(qi * t_), qi);
}

double Pose::TranslationDistance(const Pose& a, const Pose& b) {
  return (a.t_ - b.t_).norm();
}

double Pose::RotationDistanceDeg(const Pose& a, const Pose& b) {
  const double d = std::min(1.0, std::abs(a.q_.dot(b.q_)));
  return 2.0 * std::acos(d) * 180.0 / M_PI;
}

Pose Pose::Interpolate(const Pose& a, const Pose& b, double alpha) {
  return Pose((1.0 - alpha) * a.t_ + alpha * b.t_, a.q_.slerp(alpha, b.q_));
}

void Pose::print(const std::string& label) const {
  std::cout << (label.empty() ? "" : label + ": ") << *this << std::endl;
}

bool Pose::equals(const Pose& other, double tol) const {
  // q and -q are the same rotation; the canonical sign makes them equal except at qw == 0.
  const double dq = std::min((q_.coeffs() - other.q_.coeffs()).cwiseAbs().maxCoeff(),
                             (q_.coeffs() + other.q_.coeffs()).cwiseAbs().maxCoeff());
  return (t_ - other.t_).cwiseAbs().maxCoeff() <= tol && dq <= tol;
}

std::ostream& operator<<(std::ostream& os, const Pose& p) {
  const Vector7d v = p.ToVector7();
  os << "Pose(t=[" << v(0) << ", " << v(1) << ", " << v(2) << "], q(xyzw)=[" << v(3) << ", "
     << v(4) << ", " << v(5) << ", " << v(6) << "])";
  return os;
}

std::optional<Pose> InterpolateAt(const std::vector<StampedPose>& trajectory, double stamp,
                                  double max_gap) {
  if (trajectory.empty()) return std::nullopt;
  if (stamp < trajectory.front().stamp || stamp > trajectory.back().stamp) return std::nullopt;
  auto hi = std::lower_bound(trajectory.begin(), trajectory.end(), stamp,
                             [](const StampedPose& p, double s) { return p.stamp < s; });
  if (hi->stamp == stamp) return hi->pose;
  auto lo = hi - 1;
  const double gap = hi->stamp - lo->stamp;
  if (gap > max_gap) return std::nullopt;
  return Pose::Interpolate(lo->pose, hi->pose, (stamp - lo->stamp) / gap);
}

}  // namespace p2i::scene
