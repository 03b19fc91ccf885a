#include "fullarm/haptics/primitives.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace fullarm::haptics {

using Eigen::Vector3d;

namespace {

// Collects vertices and triangles; build() welds the shared seams of the face grids.
struct MeshBuilder {
  std::vector<Vector3d> v;
  std::vector<Eigen::Vector3i> t;

  int add(const Vector3d& p) {
    v.push_back(p);
    return static_cast<int>(v.size()) - 1;
  }
  // Grid over the planar quad c00 -> c10 -> c11 -> c01 (counter-clockwise seen from outside),
  // with squares no longer than max_edge along either side.
  void quad(const Vector3d& c00, const Vector3d& c10, const Vector3d& c11, const Vector3d& c01, double max_edge) {
    const int nu = std::max(1, static_cast<int>(std::ceil((c10 - c00).norm() / max_edge - 1e-9)));
    const int nv = std::max(1, static_cast<int>(std::ceil((c01 - c00).norm() / max_edge - 1e-9)));
    const int base = static_cast<int>(v.size());
    for (int j = 0; j <= nv; ++j) {
      for (int i = 0; i <= nu; ++i) {
        const double s = static_cast<double>(i) / nu;
        const double r = static_cast<double>(j) / nv;
        add((1 - s) * (1 - r) * c00 + s * (1 - r) * c10 + s * r * c11 + (1 - s) * r * c01);
      }
    }
    for (int j = 0; j < nv; ++j) {
      for (int i = 0; i < nu; ++i) {
        const int a = base + j * (nu + 1) + i;
        const int b = a + 1;
        const int c = a + nu + 2;
        const int d = a + nu + 1;
        t.emplace_back(a, b, c);
        t.emplace_back(a, c, d);
      }
    }
  }
  TriMesh build(const std::string& source, double scale) {
    return TriMesh::build(source, std::move(v), std::move(t), 1e-9 * scale);
  }
};

void requirePositive(const std::string& source, const char* what, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw MeshError(source, std::string(what) + " must be a finite value > 0, got " + std::to_string(value));
  }
}

void requireAtLeast(const std::string& source, const char* what, int value, int min) {
  if (value < min) {
    throw MeshError(source,
                    std::string(what) + " must be >= " + std::to_string(min) + ", got " + std::to_string(value));
  }
}

// Extrudes a counter-clockwise polygon (x-y) along z over [-len/2, len/2]: side quads only.
void extrudeSides(MeshBuilder& mb, const std::vector<Eigen::Vector2d>& poly, double length, double max_edge) {
  const double h = 0.5 * length;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& p = poly[i];
    const Eigen::Vector2d& q = poly[(i + 1) % poly.size()];
    mb.quad({p.x(), p.y(), -h}, {q.x(), q.y(), -h}, {q.x(), q.y(), h}, {p.x(), p.y(), h}, max_edge);
  }
}

// Axis-aligned rectangle [x0,x1] x [y0,y1] at height z, facing +z (up = true) or -z.
void capRect(MeshBuilder& mb, double x0, double x1, double y0, double y1, double z, bool up, double max_edge) {
  if (up) {
    mb.quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, max_edge);
  } else {
    mb.quad({x0, y0, z}, {x0, y1, z}, {x1, y1, z}, {x1, y0, z}, max_edge);
  }
}

}  // namespace

TriMesh makeBox(const Vector3d& size_m, double max_edge_m) {
  const std::string src = "makeBox";
  for (int k = 0; k < 3; ++k) requirePositive(src, "size_m", size_m[k]);
  requirePositive(src, "max_edge_m", max_edge_m);
  MeshBuilder mb;
  const Vector3d h = 0.5 * size_m;
  extrudeSides(mb, {{-h.x(), -h.y()}, {h.x(), -h.y()}, {h.x(), h.y()}, {-h.x(), h.y()}}, size_m.z(), max_edge_m);
  capRect(mb, -h.x(), h.x(), -h.y(), h.y(), h.z(), true, max_edge_m);
  capRect(mb, -h.x(), h.x(), -h.y(), h.y(), -h.z(), false, max_edge_m);
  return mb.build(src, size_m.maxCoeff());
}

TriMesh makeCapsule(const Vector3d& from_m, const Vector3d& to_m, double radius_m, int segments, int rings) {
  const std::string src = "makeCapsule";
  requirePositive(src, "radius_m", radius_m);
  requireAtLeast(src, "segments", segments, 3);
  requireAtLeast(src, "rings", rings, 1);
  if (!from_m.allFinite() || !to_m.allFinite()) throw MeshError(src, "segment end points must be finite");
  const Vector3d axis = to_m - from_m;
  const double len = axis.norm();
  // Local frame with z along the axis (any z when the segment is a point: a sphere).
  const Vector3d z = len > 0.0 ? Vector3d(axis / len) : Vector3d::UnitZ();
  const Vector3d x = z.unitOrthogonal();
  const Vector3d y = z.cross(x);
  MeshBuilder mb;
  // Latitude rows from the bottom pole to the top pole; the two equators are separated by the
  // cylinder (or coincide for a sphere, where the weld joins them).
  std::vector<std::pair<double, const Vector3d*>> rows;  // (latitude, centre)
  const double pi = std::numbers::pi;
  for (int k = 1; k <= rings; ++k) rows.emplace_back(-0.5 * pi + 0.5 * pi * k / rings, &from_m);
  for (int k = 0; k < rings; ++k) rows.emplace_back(0.5 * pi * k / rings, &to_m);
  const int bottom = mb.add(from_m - radius_m * z);
  std::vector<int> row_start;
  for (const auto& [lat, centre] : rows) {
    row_start.push_back(static_cast<int>(mb.v.size()));
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * pi * s / segments;
      mb.add(*centre + radius_m * (std::cos(lat) * (std::cos(phi) * x + std::sin(phi) * y) + std::sin(lat) * z));
    }
  }
  const int top = mb.add(to_m + radius_m * z);
  const int nrows = static_cast<int>(rows.size());
  for (int s = 0; s < segments; ++s) {
    const int s1 = (s + 1) % segments;
    mb.t.emplace_back(bottom, row_start[0] + s1, row_start[0] + s);
    mb.t.emplace_back(top, row_start[static_cast<std::size_t>(nrows - 1)] + s,
                      row_start[static_cast<std::size_t>(nrows - 1)] + s1);
    for (int r = 0; r + 1 < nrows; ++r) {
      const int a = row_start[static_cast<std::size_t>(r)] + s;
      const int b = row_start[static_cast<std::size_t>(r)] + s1;
      const int c = row_start[static_cast<std::size_t>(r + 1)] + s1;
      const int d = row_start[static_cast<std::size_t>(r + 1)] + s;
      mb.t.emplace_back(a, b, c);
      mb.t.emplace_back(a, c, d);
    }
  }
  return mb.build(src, len + 2.0 * radius_m);
}

TriMesh makeCylinder(double radius_m, double length_m, int segments, double max_edge_m) {
  const std::string src = "makeCylinder";
  requirePositive(src, "radius_m", radius_m);
  requirePositive(src, "length_m", length_m);
  requireAtLeast(src, "segments", segments, 3);
  requirePositive(src, "max_edge_m", max_edge_m);
  std::vector<Eigen::Vector2d> poly;
  const double pi = std::numbers::pi;
  for (int s = 0; s < segments; ++s) {
    const double phi = 2.0 * pi * s / segments;
    poly.emplace_back(radius_m * std::cos(phi), radius_m * std::sin(phi));
  }
  MeshBuilder mb;
  // Side quads one segment wide, split axially only.
  const double h = 0.5 * length_m;
  for (int s = 0; s < segments; ++s) {
    const auto& p = poly[static_cast<std::size_t>(s)];
    const auto& q = poly[static_cast<std::size_t>((s + 1) % segments)];
    mb.quad({p.x(), p.y(), -h}, {q.x(), q.y(), -h}, {q.x(), q.y(), h}, {p.x(), p.y(), h},
            std::max(max_edge_m, (q - p).norm()));
  }
  const int top = mb.add({0, 0, h});
  const int bottom = mb.add({0, 0, -h});
  for (int s = 0; s < segments; ++s) {
    const auto& p = poly[static_cast<std::size_t>(s)];
    const auto& q = poly[static_cast<std::size_t>((s + 1) % segments)];
    const int pt = mb.add({p.x(), p.y(), h});
    const int qt = mb.add({q.x(), q.y(), h});
    mb.t.emplace_back(top, pt, qt);
    const int pb = mb.add({p.x(), p.y(), -h});
    const int qb = mb.add({q.x(), q.y(), -h});
    mb.t.emplace_back(bottom, qb, pb);
  }
  return mb.build(src, std::max(radius_m, length_m));
}

TriMesh makeRectangularFrame(double outer_width_m, double outer_height_m, double bar_width_m, double depth_m,
                             double max_edge_m) {
  const std::string src = "makeRectangularFrame";
  requirePositive(src, "outer_width_m", outer_width_m);
  requirePositive(src, "outer_height_m", outer_height_m);
  requirePositive(src, "bar_width_m", bar_width_m);
  requirePositive(src, "depth_m", depth_m);
  requirePositive(src, "max_edge_m", max_edge_m);
  if (2.0 * bar_width_m >= std::min(outer_width_m, outer_height_m)) {
    throw MeshError(src, "bar_width_m must be less than half the outer width and height (the opening would vanish)");
  }
  const double X = 0.5 * outer_width_m;
  const double Y = 0.5 * outer_height_m;
  const double x = X - bar_width_m;
  const double y = Y - bar_width_m;
  const double h = 0.5 * depth_m;
  MeshBuilder mb;
  // Outer sides (counter-clockwise polygon) and inner sides (clockwise: normals into the opening).
  // Outer outline split where the ring's rectangles meet it, so the seams match.
  extrudeSides(
      mb, {{-X, -Y}, {-x, -Y}, {x, -Y}, {X, -Y}, {X, -y}, {X, y}, {X, Y}, {x, Y}, {-x, Y}, {-X, Y}, {-X, y}, {-X, -y}},
      depth_m, max_edge_m);
  extrudeSides(mb, {{-x, -y}, {-x, y}, {x, y}, {x, -y}}, depth_m, max_edge_m);
  // Front and back rings as 8 rectangles whose shared sides match.
  const double xs[4] = {-X, -x, x, X};
  const double ys[4] = {-Y, -y, y, Y};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == 1 && j == 1) continue;  // the opening
      capRect(mb, xs[i], xs[i + 1], ys[j], ys[j + 1], h, true, max_edge_m);
      capRect(mb, xs[i], xs[i + 1], ys[j], ys[j + 1], -h, false, max_edge_m);
    }
  }
  return mb.build(src, std::max({outer_width_m, outer_height_m, depth_m}));
}

TriMesh makeIBeam(double height_m, double flange_width_m, double flange_thickness_m, double web_thickness_m,
                  double length_m, double max_edge_m) {
  const std::string src = "makeIBeam";
  requirePositive(src, "height_m", height_m);
  requirePositive(src, "flange_width_m", flange_width_m);
  requirePositive(src, "flange_thickness_m", flange_thickness_m);
  requirePositive(src, "web_thickness_m", web_thickness_m);
  requirePositive(src, "length_m", length_m);
  requirePositive(src, "max_edge_m", max_edge_m);
  if (2.0 * flange_thickness_m >= height_m) throw MeshError(src, "flange_thickness_m must be < height_m / 2");
  if (web_thickness_m >= flange_width_m) throw MeshError(src, "web_thickness_m must be < flange_width_m");
  const double W = 0.5 * flange_width_m;
  const double w = 0.5 * web_thickness_m;
  const double H = 0.5 * height_m;
  const double g = H - flange_thickness_m;
  MeshBuilder mb;
  // Counter-clockwise I outline, split where the cap rectangles meet it.
  extrudeSides(mb,
               {{-W, -H},
                {-w, -H},
                {w, -H},
                {W, -H},
                {W, -g},
                {w, -g},
                {w, g},
                {W, g},
                {W, H},
                {w, H},
                {-w, H},
                {-W, H},
                {-W, g},
                {-w, g},
                {-w, -g},
                {-W, -g}},
               length_m, max_edge_m);
  const double L = 0.5 * length_m;
  for (const double z : {L, -L}) {
    const bool up = z > 0.0;
    const double xs[4] = {-W, -w, w, W};
    for (int i = 0; i < 3; ++i) {
      capRect(mb, xs[i], xs[i + 1], -H, -g, z, up, max_edge_m);
      capRect(mb, xs[i], xs[i + 1], g, H, z, up, max_edge_m);
    }
    capRect(mb, -w, w, -g, g, z, up, max_edge_m);
  }
  return mb.build(src, std::max({height_m, flange_width_m, length_m}));
}

TriMesh makeLinkCapsuleMesh(const arm::ArmModel& model, int link, int segments, int rings) {
  if (link < 0 || link >= model.numJoints()) {
    throw MeshError("makeLinkCapsuleMesh", "link index " + std::to_string(link) + " out of range");
  }
  const arm::Joint& joint = model.joints[static_cast<std::size_t>(link)];
  if (joint.geometry.type != arm::LinkGeometry::Type::kCapsule) {
    throw MeshError("makeLinkCapsuleMesh(" + joint.name + ")", "link geometry is not a capsule");
  }
  TriMesh mesh = makeCapsule(joint.geometry.from_m, joint.geometry.to_m, joint.geometry.radius_m, segments, rings);
  // Rename the source so errors and reports name the link.
  std::vector<Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  for (int i = 0; i < mesh.numTriangles(); ++i) t.push_back(mesh.triangle(i));
  return TriMesh::build("link " + joint.name + " capsule", std::move(v), std::move(t));
}

}  // namespace fullarm::haptics
