#include "core/polygon_ops.hpp"

#include "core/clipper_convert.hpp"

namespace nonplanar {

double area(const std::vector<ExPolygon>& polys) {
  auto a = [](const Polygon& p) {
    double s = 0;
    for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
      s += p[j].x() * p[i].y() - p[i].x() * p[j].y();
    return 0.5 * s;
  };
  double s = 0;
  for (const ExPolygon& e : polys) {
    s += std::abs(a(e.contour));
    for (const Polygon& h : e.holes) s -= std::abs(a(h));
  }
  return s;
}

}  // namespace nonplanar

namespace nonplanar::clip {
namespace {

using ClipperLib::Path;
using ClipperLib::Paths;

Path to_path(const Polygon& p) {
  Path out;
  out.reserve(p.size());
  for (const Vec2& v : p) out.push_back(to_clipper(v));
  return out;
}
Polygon to_polygon(const Path& p) {
  Polygon out;
  out.reserve(p.size());
  for (const auto& v : p) out.push_back(from_clipper(v));
  return out;
}
Paths to_paths(const ExPolygons& a) {
  Paths out;
  for (const ExPolygon& e : a) {
    out.push_back(to_path(e.contour));
    for (const Polygon& h : e.holes) out.push_back(to_path(h));
  }
  return out;
}

// Outer contours with their direct holes; islands inside holes become new ExPolygons.
void collect(const ClipperLib::PolyNode& node, ExPolygons& out) {
  for (const ClipperLib::PolyNode* child : node.Childs) {
    ExPolygon e;
    e.contour = to_polygon(child->Contour);
    for (const ClipperLib::PolyNode* hole : child->Childs) {
      e.holes.push_back(to_polygon(hole->Contour));
      collect(*hole, out);
    }
    out.push_back(std::move(e));
  }
}

ExPolygons run(ClipperLib::ClipType type, const Paths& subject, const Paths& clip,
               ClipperLib::PolyFillType fill) {
  ClipperLib::Clipper c;
  c.AddPaths(subject, ClipperLib::ptSubject, true);
  if (!clip.empty()) c.AddPaths(clip, ClipperLib::ptClip, true);
  ClipperLib::PolyTree tree;
  c.Execute(type, tree, fill, fill);
  ExPolygons out;
  collect(tree, out);
  return out;
}

}  // namespace

ExPolygons union_loops(const std::vector<Polygon>& loops) {
  Paths p;
  for (const Polygon& l : loops) p.push_back(to_path(l));
  return run(ClipperLib::ctUnion, p, {}, ClipperLib::pftNonZero);
}

ExPolygons union_ex(const ExPolygons& a) {
  return run(ClipperLib::ctUnion, to_paths(a), {}, ClipperLib::pftNonZero);
}

ExPolygons diff_ex(const ExPolygons& a, const ExPolygons& b) {
  if (b.empty()) return a;
  return run(ClipperLib::ctDifference, to_paths(a), to_paths(b), ClipperLib::pftNonZero);
}

ExPolygons intersection_ex(const ExPolygons& a, const ExPolygons& b) {
  if (a.empty() || b.empty()) return {};
  return run(ClipperLib::ctIntersection, to_paths(a), to_paths(b), ClipperLib::pftNonZero);
}

ExPolygons offset_ex(const ExPolygons& a, double delta) {
  if (a.empty()) return {};
  ClipperLib::ClipperOffset co(3.0, 0.25 * kScale * 1e-3);
  co.AddPaths(to_paths(a), ClipperLib::jtMiter, ClipperLib::etClosedPolygon);
  ClipperLib::PolyTree tree;
  co.Execute(tree, delta * kScale);
  ExPolygons out;
  collect(tree, out);
  return out;
}

std::vector<Polyline> clip_polylines(const std::vector<Polyline>& lines, const ExPolygons& region) {
  if (lines.empty() || region.empty()) return {};
  ClipperLib::Clipper c;
  for (const Polyline& l : lines) c.AddPath(to_path(l), ClipperLib::ptSubject, false);
  c.AddPaths(to_paths(region), ClipperLib::ptClip, true);
  ClipperLib::PolyTree tree;
  c.Execute(ClipperLib::ctIntersection, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
  Paths open;
  ClipperLib::OpenPathsFromPolyTree(tree, open);
  std::vector<Polyline> out;
  for (const Path& p : open) out.push_back(to_polygon(p));
  return out;
}

ExPolygons simplify(const ExPolygons& a, double tolerance) {
  Paths p = to_paths(a);
  ClipperLib::CleanPolygons(p, tolerance * kScale);
  return run(ClipperLib::ctUnion, p, {}, ClipperLib::pftNonZero);
}

}  // namespace nonplanar::clip
