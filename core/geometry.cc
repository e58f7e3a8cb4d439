// SPDX-License-Identifier: Apache-2.0
#include "core/geometry.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb {

absl::Status Polyline3::Validate(const std::string& what) const {
  if (points.size() < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ".points: needs at least 2 points, has ", points.size()));
  }
  if (radii.size() != points.size()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ".radii: has ", radii.size(),
                                                   " entries for ", points.size(), " points"));
  }
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".points[", i, "] is not finite"));
    }
    if (!std::isfinite(radii[i]) || radii[i] <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ".radii[", i, "] must be finite and > 0, is ", radii[i]));
    }
  }
  return absl::OkStatus();
}

double Polyline3::Length() const {
  double length = 0.0;
  for (size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

std::vector<double> Polyline3::ArcLengths() const {
  std::vector<double> s(points.size(), 0.0);
  for (size_t i = 1; i < points.size(); ++i) s[i] = s[i - 1] + (points[i] - points[i - 1]).norm();
  return s;
}

namespace {

// Index i of the segment [i, i+1] containing arc length s, and the fraction along it.
void Locate(const std::vector<double>& arc, double s, size_t* i, double* f) {
  const size_t n = arc.size();
  if (n < 2) {
    *i = 0;
    *f = 0.0;
    return;
  }
  s = std::clamp(s, 0.0, arc.back());
  const auto it = std::upper_bound(arc.begin(), arc.end(), s);
  size_t k = static_cast<size_t>(it - arc.begin());
  k = std::clamp<size_t>(k, 1, n - 1);
  *i = k - 1;
  const double len = arc[k] - arc[k - 1];
  *f = len > 0.0 ? (s - arc[k - 1]) / len : 0.0;
}

}  // namespace

Eigen::Vector3d Polyline3::PointAt(double s) const { return PointAt(s, ArcLengths()); }

double Polyline3::RadiusAt(double s) const { return RadiusAt(s, ArcLengths()); }

Eigen::Vector3d Polyline3::PointAt(double s, const std::vector<double>& arc) const {
  if (points.empty()) return Eigen::Vector3d::Zero();
  if (points.size() == 1) return points[0];
  size_t i;
  double f;
  Locate(arc, s, &i, &f);
  return points[i] + f * (points[i + 1] - points[i]);
}

double Polyline3::RadiusAt(double s, const std::vector<double>& arc) const {
  if (radii.empty()) return 0.0;
  if (radii.size() == 1) return radii[0];
  size_t i;
  double f;
  Locate(arc, s, &i, &f);
  return radii[i] + f * (radii[i + 1] - radii[i]);
}

double Polyline3::MeanBaseDiameter(double span_m) const {
  const std::vector<double> arc = ArcLengths();
  const double span = std::min(span_m, arc.back());
  if (span <= 0.0) return 2.0 * radii.front();
  // The radius is linear in arc length on each segment, so the trapezoid rule is exact.
  double area = 0.0;
  for (size_t i = 0; i + 1 < arc.size() && arc[i] < span; ++i) {
    const double s1 = std::min(arc[i + 1], span);
    area += 0.5 * (radii[i] + RadiusAt(s1)) * (s1 - arc[i]);
  }
  return 2.0 * area / span;
}

Eigen::Vector3d Polyline3::TangentAt(double s) const { return TangentAt(s, ArcLengths()); }

Eigen::Vector3d Polyline3::TangentAt(double s, const std::vector<double>& arc) const {
  if (points.size() < 2) return Eigen::Vector3d::UnitX();
  size_t i;
  double f;
  Locate(arc, s, &i, &f);
  const Eigen::Vector3d d = points[i + 1] - points[i];
  const double n = d.norm();
  return n > 0.0 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitX();
}

double Polyline3::Project(const Eigen::Vector3d& p, double* distance_m) const {
  double best_s = 0.0;
  double best_d = points.empty() ? 0.0 : (p - points[0]).norm();
  double arc = 0.0;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    double t = 0.0;
    const double d = PointSegmentDistance(p, points[i], points[i + 1], &t);
    const double length = (points[i + 1] - points[i]).norm();
    if (d < best_d) {
      best_d = d;
      best_s = arc + t * length;
    }
    arc += length;
  }
  if (distance_m != nullptr) *distance_m = best_d;
  return best_s;
}

void Polyline3::TruncateAt(double s) {
  if (points.size() < 2) return;
  const std::vector<double> arc = ArcLengths();
  size_t i;
  double f;
  Locate(arc, s, &i, &f);
  const Eigen::Vector3d end = points[i] + f * (points[i + 1] - points[i]);
  const double end_radius = radii[i] + f * (radii[i + 1] - radii[i]);
  points.resize(i + 1);
  radii.resize(i + 1);
  if (f > 1e-9 || points.size() < 2) {
    points.push_back(end);
    radii.push_back(end_radius);
  }
}

std::vector<Eigen::Vector3d> Polyline3::Sample(double step_m) const {
  std::vector<Eigen::Vector3d> out;
  if (points.empty()) return out;
  const double length = Length();
  const int n = std::max(1, static_cast<int>(std::ceil(length / std::max(step_m, 1e-6))));
  out.reserve(n + 1);
  for (int k = 0; k <= n; ++k) out.push_back(PointAt(length * k / n));
  return out;
}

Polyline3 Polyline3::Resampled(double step_m) const {
  Polyline3 out;
  if (points.empty()) return out;
  const std::vector<double> arc = ArcLengths();
  const double length = arc.back();
  const int n = std::max(2, static_cast<int>(std::lround(length / step_m)) + 1);
  out.points.reserve(n);
  out.radii.reserve(n);
  for (int k = 0; k < n; ++k) {
    size_t i = 0;
    double f = 0.0;
    Locate(arc, length * k / (n - 1), &i, &f);
    if (points.size() == 1) {
      out.points.push_back(points[0]);
      out.radii.push_back(radii.empty() ? 0.0 : radii[0]);
      continue;
    }
    out.points.push_back(points[i] + f * (points[i + 1] - points[i]));
    out.radii.push_back(radii[i] + f * (radii[i + 1] - radii[i]));
  }
  return out;
}

double PointSegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, double* t) {
  const Eigen::Vector3d ab = b - a;
  const double denom = ab.squaredNorm();
  double u = denom > 0.0 ? (p - a).dot(ab) / denom : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  if (t != nullptr) *t = u;
  return (a + u * ab - p).norm();
}

// Closest points of two segments (Ericson, "Real-Time Collision Detection", 5.1.9).
double SegmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                              const Eigen::Vector3d& q0, const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0;
  const Eigen::Vector3d d2 = q1 - q0;
  const Eigen::Vector3d r = p0 - q0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  constexpr double kEps = 1e-18;
  double s = 0.0;
  double t = 0.0;
  if (a <= kEps && e <= kEps) return r.norm();
  if (a <= kEps) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEps) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > kEps ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

}  // namespace vb
