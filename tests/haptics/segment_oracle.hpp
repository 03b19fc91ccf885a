#pragma once
/// @file
/// An exact segment-triangle distance oracle for the haptics tests, independent of the library's
/// closest-point routines: long double throughout, the point-triangle Voronoi regions written out
/// again, and a golden-section search over the segment parameter (the distance from a point of
/// the segment to the triangle is convex in that parameter).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace fullarm::haptics::test {

using Vec3L = Eigen::Matrix<long double, 3, 1>;

inline Vec3L toLong(const Eigen::Vector3d& v) {
  return v.cast<long double>();
}

// Distance from p to triangle (a, b, c) in long double (the Voronoi regions of Ericson 5.1.5,
// written out again here, independent of the library's routines).
inline long double pointTriangleDistance(const Vec3L& p, const Vec3L& a, const Vec3L& b, const Vec3L& c) {
  const Vec3L ab = b - a;
  const Vec3L ac = c - a;
  const Vec3L ap = p - a;
  const long double d1 = ab.dot(ap);
  const long double d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vec3L bp = p - b;
  const long double d3 = ab.dot(bp);
  const long double d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const long double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - (d1 / (d1 - d3)) * ab).norm();
  const Vec3L cp = p - c;
  const long double d5 = ab.dot(cp);
  const long double d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const long double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - (d2 / (d2 - d6)) * ac).norm();
  const long double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).norm();
  const long double denom = 1 / (va + vb + vc);
  return (ap - ab * (vb * denom) - ac * (vc * denom)).norm();
}

// Segment-triangle distance: the distance from a point of the segment to the triangle is convex
// in the segment parameter, so a golden-section search on [0, 1] (120 steps, long double) finds
// its minimum to far below 1e-12 m.
inline long double segmentTriangleOracle(const Vec3L& p0, const Vec3L& p1, const Vec3L& a, const Vec3L& b,
                                         const Vec3L& c) {
  const auto f = [&](long double s) { return pointTriangleDistance(p0 + s * (p1 - p0), a, b, c); };
  const long double g = (std::sqrt(5.0L) - 1) / 2;
  long double lo = 0;
  long double hi = 1;
  long double x1 = hi - g * (hi - lo);
  long double x2 = lo + g * (hi - lo);
  long double f1 = f(x1);
  long double f2 = f(x2);
  for (int i = 0; i < 120; ++i) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0), f(1)});
}

}  // namespace fullarm::haptics::test
