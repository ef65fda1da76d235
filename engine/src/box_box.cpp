#include "box_box.hpp"

#include "box_distance.hpp"

#include <algorithm>
#include <cmath>

namespace tumble {
namespace {

// A face axis of B (or an edge axis) replaces the best face axis of A only when it separates
// by this much more (m): near-ties (a box resting flat on another) then keep one reference
// face from step to step, so feature ids and the warm-started impulses persist.
constexpr double kFaceTolerance = 1e-4;
constexpr double kEdgeTolerance = 5e-4;
// ... plus this fraction of the smaller box's least half extent: an edge axis close to a face
// normal must beat it clearly, or a box tilted on a face would get one edge point and rock.
constexpr double kEdgeRelativeTolerance = 0.02;
constexpr int kMaxClipped = 8;
// A vertex of the incident face this far outside a side plane of the reference face still
// counts as inside (m). Equal boxes stacked flush have their vertices exactly on those
// planes; without the tolerance round-off would flip them between "vertex" and "clipped
// point" from step to step, changing their ids and losing the warm start.
constexpr double kClipTolerance = 1e-4;

/// A vertex of the clipped incident face: the incident edges and clip planes it lies on
/// (4 bits each) identify it from step to step.
struct ClipVertex {
  Vec3 p;
  unsigned edges;
  unsigned planes;
};

struct Polygon {
  int count = 0;
  std::array<ClipVertex, kMaxClipped> v;  // [0, count) in use
};

/// Sutherland–Hodgman: writes to `out` the part of `in` where distance(q) ≤ 0 (one side plane
/// of the reference face) and returns true; returns false, writing nothing, when all of `in`
/// is inside (the part is `in` itself). Each vertex's distance is found once.
template <typename Distance>
bool clip(const Polygon& in, int plane, Distance distance, Polygon& out) {
  std::array<double, kMaxClipped> d;
  bool inside = true;
  for (int i = 0; i < in.count; ++i) {
    d[i] = distance(in.v[i].p) - kClipTolerance;
    inside = inside && d[i] <= 0.0;
  }
  if (inside) return false;
  out.count = 0;
  for (int i = 0, prev = in.count - 1; i < in.count; prev = i++) {
    const ClipVertex& a = in.v[prev];
    const ClipVertex& b = in.v[i];
    const double da = d[prev], db = d[i];
    if ((da <= 0.0) != (db <= 0.0)) {
      ClipVertex x;
      x.p = a.p + (da / (da - db)) * (b.p - a.p);
      x.edges = a.edges & b.edges;
      x.planes = (a.planes & b.planes) | (1u << plane);
      if (out.count < kMaxClipped) out.v[out.count++] = x;
    }
    if (db <= 0.0 && out.count < kMaxClipped) out.v[out.count++] = b;
  }
  return true;
}

struct Box {
  const BodyState& s;
  const BodyConstants& c;
};

/// Face–face (or face–edge, face–vertex) case: the incident face of `inc` clipped against the
/// side planes of the reference face of `ref`; `n_ref` points from ref to inc.
int clip_faces(const Box& ref, int ref_axis, const Vec3& n_ref, const Box& inc, double margin,
               std::uint32_t id_base, std::array<ManifoldPoint, kMaxClipped>& out) {
  const Vec3 ref_center = ref.s.x + ref.c.half_extents(ref_axis) * n_ref;
  const int ua = (ref_axis + 1) % 3, va = (ref_axis + 2) % 3;
  const Vec3 u = ref.s.R.col(ua), v = ref.s.R.col(va);
  const double hu = ref.c.half_extents(ua), hv = ref.c.half_extents(va);

  const Vec3 dots = inc.s.R.transpose() * n_ref;
  int k = 0;
  dots.cwiseAbs().maxCoeff(&k);
  const double side = dots(k) > 0.0 ? -1.0 : 1.0;  // incident face faces the reference
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  const Vec3 c = inc.s.x + side * inc.c.half_extents(k) * inc.s.R.col(k);
  const Vec3 e1 = inc.c.half_extents(k1) * inc.s.R.col(k1);
  const Vec3 e2 = inc.c.half_extents(k2) * inc.s.R.col(k2);
  std::array<Polygon, 2> buffers;  // the polygon and the next clip's output, in turn
  Polygon* poly = &buffers[0];
  Polygon* next = &buffers[1];
  poly->count = 4;
  const Vec3 corners[4] = {c + e1 + e2, c - e1 + e2, c - e1 - e2, c + e1 - e2};
  for (int i = 0; i < 4; ++i) {
    // Vertex i lies on incident edges i (to i+1) and i−1.
    poly->v[i] = {corners[i], (1u << i) | (1u << ((i + 3) % 4)), 0u};
  }
  auto clip_by = [&](int plane, auto distance) {
    if (clip(*poly, plane, distance, *next)) std::swap(poly, next);
  };
  clip_by(0, [&](const Vec3& q) { return (q - ref_center).dot(u) - hu; });
  clip_by(1, [&](const Vec3& q) { return -(q - ref_center).dot(u) - hu; });
  clip_by(2, [&](const Vec3& q) { return (q - ref_center).dot(v) - hv; });
  clip_by(3, [&](const Vec3& q) { return -(q - ref_center).dot(v) - hv; });

  const std::uint32_t inc_face = static_cast<std::uint32_t>(2 * k + (side > 0.0 ? 1 : 0));
  int n = 0;
  for (int i = 0; i < poly->count; ++i) {
    const ClipVertex& q = poly->v[i];
    const double depth = (q.p - ref_center).dot(n_ref);
    if (depth >= margin) continue;
    ManifoldPoint& p = out[n++];
    p.position = q.p - (0.5 * depth) * n_ref;
    p.separation = depth;
    p.id = id_base | (inc_face << 8) | (q.planes << 4) | q.edges;
  }
  return n;
}

/// Chooses 4 of n points: the deepest, the farthest from it, the largest triangle, then the
/// point farthest outside that triangle's base on the other side (Gregorius, "Robust contact
/// creation for physics simulations", GDC 2015).
int reduce_to_four(const std::array<ManifoldPoint, kMaxClipped>& in, int n, const Vec3& normal,
                   std::array<ManifoldPoint, kMaxManifoldPoints>& out) {
  if (n <= kMaxManifoldPoints) {
    std::copy(in.begin(), in.begin() + n, out.begin());
    return n;
  }
  int i0 = 0;
  for (int i = 1; i < n; ++i)
    if (in[i].separation < in[i0].separation) i0 = i;
  int i1 = -1;
  double best = -1.0;
  for (int i = 0; i < n; ++i) {
    const double d = (in[i].position - in[i0].position).squaredNorm();
    if (i != i0 && d > best) best = d, i1 = i;
  }
  auto area = [&](int a, int b, int q) {
    return (in[b].position - in[a].position).cross(in[q].position - in[a].position).dot(normal);
  };
  int i2 = -1;
  best = -1.0;
  for (int i = 0; i < n; ++i) {
    if (i == i0 || i == i1) continue;
    const double a = std::abs(area(i0, i1, i));
    if (a > best) best = a, i2 = i;
  }
  const double sign2 = area(i0, i1, i2) >= 0.0 ? 1.0 : -1.0;
  int i3 = -1;
  best = -INFINITY;
  for (int i = 0; i < n; ++i) {
    if (i == i0 || i == i1 || i == i2) continue;
    // Prefer the point on the far side of i0–i1 from i2; otherwise the one adding most area
    // to the triangle's other edges.
    const double a = -sign2 * area(i0, i1, i);
    const double b = std::max(-sign2 * area(i1, i2, i), -sign2 * area(i2, i0, i));
    const double score = std::max(a, b);
    if (score > best) best = score, i3 = i;
  }
  out[0] = in[i0];
  out[1] = in[i1];
  out[2] = in[i2];
  out[3] = in[i3];
  return 4;
}

/// Edge–edge case: the closest points of edge i of A and edge j of B along the axis
/// a_i × b_j. Returns false when the closest points fall at an end of either edge: the edges
/// do not cross, the contact is really a vertex or face one, and the face case handles it.
bool edge_contact(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                  const BodyConstants& cb, int edge_i, int edge_j, const Vec3& axis,
                  BoxManifold& m) {
  Vec3 n = axis;
  if (n.dot(b.x - a.x) < 0.0) n = -n;
  EdgeNearest e;
  if (!extreme_edges_nearest(a, ca.half_extents, edge_i, b, cb.half_extents, edge_j, n, e))
    return false;
  m.normal = n;
  m.count = 1;
  m.points[0].position = 0.5 * (e.on_a + e.on_b);
  m.points[0].separation = (e.on_b - e.on_a).dot(n);
  m.points[0].id = (1u << 31) | (static_cast<std::uint32_t>(edge_i * 3 + edge_j) << 8) | e.corners;
  return true;
}

// kNearestPointsId: box–box ids set bit 31 for an edge pair and bits 12–15 for a face.
constexpr std::uint32_t kNearestPointsId = 1u << 30;

/// The manifold when no axis separates boxes a and b by the margin but the reference face's
/// clipping keeps no point: two corners, or a corner and an edge, nearest each other beside
/// the reference face, where no separating axis points along the gap. One point along the
/// line between the boxes' nearest points, whose separation is their distance, when they are
/// apart (`apart`: some axis separates them) by less than the margin (else nothing). Without
/// it a cube flying corner first at another's corner at 40 m/s got no contact until it was
/// 23 cm inside.
void nearest_points_contact(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                            const BodyConstants& cb, double margin, bool apart, BoxManifold& m) {
  if (!apart) return;  // overlapping: no line between the boxes
  const BoxNearest near = box_nearest(a, ca, b, cb);
  if (!(near.distance > 0.0 && near.distance < margin)) return;
  m.normal = (near.on_b - near.on_a) / near.distance;
  m.count = 1;
  m.points[0].position = 0.5 * (near.on_a + near.on_b);
  m.points[0].separation = near.distance;
  m.points[0].id = kNearestPointsId;
}

/// Boxes a and b in a's frame: C(i, j) = a_i · b_j, |C| (plus ε, which keeps near-parallel
/// edge pairs from producing a false separating axis: Gottschalk) and the centres' offset
/// b.x − a.x in each box's own frame.
struct PairFrame {
  Mat3 C, absC;
  Vec3 da, db;
};

PairFrame pair_frame(const BodyState& a, const BodyState& b) {
  const Vec3 d = b.x - a.x;
  PairFrame f;
  f.C = a.R.transpose() * b.R;
  f.absC = f.C.cwiseAbs().array() + 1e-12;
  f.da = a.R.transpose() * d;
  f.db = b.R.transpose() * d;
  return f;
}

/// The largest separation along one box's face normals (m) and which normal gave it.
struct AxisSeparation {
  double separation = -INFINITY;
  int axis = -1;
};

/// The face axes of A, then of B: false as soon as one separates the boxes by more than
/// `margin`, else the best of each.
bool face_axes(const PairFrame& f, const Vec3& ha, const Vec3& hb, double margin,
               AxisSeparation& on_a, AxisSeparation& on_b) {
  double best_a = -INFINITY, best_b = -INFINITY;
  int axis_a = 0, axis_b = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = std::abs(f.da(i)) - (ha(i) + f.absC.row(i).dot(hb));
    if (s > margin) return false;
    if (s > best_a) best_a = s, axis_a = i;
  }
  for (int j = 0; j < 3; ++j) {
    const double s = std::abs(f.db(j)) - (f.absC.col(j).dot(ha) + hb(j));
    if (s > margin) return false;
    if (s > best_b) best_b = s, axis_b = j;
  }
  on_a = {best_a, axis_a};
  on_b = {best_b, axis_b};
  return true;
}

/// The nine edge axes a_i × b_j from C alone (Ericson §4.4.1): in A's frame the axis is
/// e_i × C(:, j), whose components i1, i2 are −C(i2, j) and C(i1, j), so its length, the
/// projection of d and both boxes' radii along it are a few products of C's entries. False as
/// soon as one separates the boxes by more than `margin`; else the best (axis = 3 i + j, or −1
/// when every pair of edges is parallel).
bool edge_axes(const PairFrame& f, const Vec3& ha, const Vec3& hb, double margin,
               AxisSeparation& best) {
  double most = -INFINITY;
  int axis = -1;
  const Mat3& C = f.C;
  const Mat3& absC = f.absC;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double len = std::sqrt(C(i1, j) * C(i1, j) + C(i2, j) * C(i2, j));
      if (len < 1e-6) continue;  // parallel edges: covered by the face axes
      const double ra = ha(i1) * absC(i2, j) + ha(i2) * absC(i1, j);
      const double rb = hb(j1) * absC(i, j2) + hb(j2) * absC(i, j1);
      const double s = (std::abs(f.da(i2) * C(i1, j) - f.da(i1) * C(i2, j)) - (ra + rb)) / len;
      if (s > margin) return false;
      if (s > most) most = s, axis = 3 * i + j;
    }
  }
  best = {most, axis};
  return true;
}

/// The face case: the incident face clipped against the reference face, on A's face axis or
/// on B's when it separates the boxes clearly more; at most four points kept. The normal
/// points from A to B.
BoxManifold face_manifold(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                          const BodyConstants& cb, const PairFrame& f, bool on_b,
                          const AxisSeparation& face, double margin) {
  BoxManifold m;
  std::array<ManifoldPoint, kMaxClipped> clipped{};
  int n = 0;
  const int axis = face.axis;
  if (on_b) {
    // Reference face on B; its normal points from B to A, the manifold normal is its opposite.
    const double sign = f.db(axis) > 0.0 ? -1.0 : 1.0;
    const Vec3 n_ref = sign * b.R.col(axis);
    const std::uint32_t ref_face = static_cast<std::uint32_t>(2 * axis + (sign > 0.0 ? 1 : 0));
    n = clip_faces(Box{b, cb}, axis, n_ref, Box{a, ca}, margin, (1u << 15) | (ref_face << 12),
                   clipped);
    m.normal = -n_ref;
  } else {
    const double sign = f.da(axis) > 0.0 ? 1.0 : -1.0;
    const Vec3 n_ref = sign * a.R.col(axis);
    const std::uint32_t ref_face = static_cast<std::uint32_t>(2 * axis + (sign > 0.0 ? 1 : 0));
    n = clip_faces(Box{a, ca}, axis, n_ref, Box{b, cb}, margin, ref_face << 12, clipped);
    m.normal = n_ref;
  }
  m.count = reduce_to_four(clipped, n, m.normal, m.points);
  return m;
}

}  // namespace

// Separating-axis test for oriented boxes (Gottschalk, Lin & Manocha, "OBBTree", SIGGRAPH
// 1996; Ericson, Real-Time Collision Detection, §4.4.1): two convex boxes are disjoint iff
// they are separated along one of 15 axes — the 3 face normals of each and the 9 cross
// products of their edge directions. The axis of greatest separation (least penetration)
// names the touching features: a face axis gives a face–face/face–edge/face–vertex contact,
// found by clipping the most anti-parallel face of the other box against the reference face's
// side planes (Ericson §5.5; Box2D-lite, Catto GDC 2006); an edge axis gives one point, the
// closest points of the two edges. Separations are signed, so the same test yields
// speculative points for boxes up to `margin` apart.
BoxManifold collide_boxes(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                          const BodyConstants& cb, double margin, double wanted) {
  const Vec3& ha = ca.half_extents;
  const Vec3& hb = cb.half_extents;
  const PairFrame f = pair_frame(a, b);
  AxisSeparation on_a, on_b, edge;
  if (!face_axes(f, ha, hb, margin, on_a, on_b) || !edge_axes(f, ha, hb, margin, edge))
    return {};
  const double best_face = std::max(on_a.separation, on_b.separation);
  const double edge_tolerance =
      kEdgeTolerance + kEdgeRelativeTolerance * std::min(ha.minCoeff(), hb.minCoeff());
  if (edge.axis >= 0 && edge.separation > best_face + edge_tolerance) {
    const int edge_i = edge.axis / 3, edge_j = edge.axis % 3;
    const Vec3 axis = a.R.col(edge_i).cross(b.R.col(edge_j)).normalized();
    BoxManifold m;
    if (edge_contact(a, ca, b, cb, edge_i, edge_j, axis, m) && m.points[0].separation < margin)
      return m;
  }
  // A clipped point lies on the incident face, so its separation along the reference normal
  // is at least that axis's separation (the least over the incident box's corners); the
  // nearest points' contact, taken when the clipping keeps none, is the boxes' distance, which
  // no axis's separation exceeds.
  const bool use_b = on_b.separation > on_a.separation + kFaceTolerance;
  const AxisSeparation& face = use_b ? on_b : on_a;
  if (face.separation > wanted) return {};
  BoxManifold m = face_manifold(a, ca, b, cb, f, use_b, face, margin);
  if (m.count == 0)
    nearest_points_contact(a, ca, b, cb, margin, std::max(best_face, edge.separation) > 0.0, m);
  return m;
}

// The same 15 axes as collide_boxes, in a's frame (Ericson, Real-Time Collision Detection,
// §4.4.1): C = R_aᵀ R_b holds the cosines between the two boxes' axes and t the centres'
// offset, so each axis's overlap is a few products. An edge axis a_i × b_j has length
// sin θ_ij; near-parallel edges (sin θ < 1e-6) are left to the face axes, which bound them.
double box_depth(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                 const BodyConstants& cb, double enough) {
  const Mat3 C = a.R.transpose() * b.R;
  const Mat3 A = C.cwiseAbs();
  const Vec3 t = a.R.transpose() * (b.x - a.x);
  const Vec3& ha = ca.half_extents;
  const Vec3& hb = cb.half_extents;
  double depth = INFINITY;
  for (int i = 0; i < 3; ++i) {
    depth = std::min(depth, ha[i] + A.row(i).dot(hb) - std::abs(t[i]));
    if (depth <= enough) return depth;
  }
  const Vec3 tb = C.transpose() * t;
  for (int j = 0; j < 3; ++j) {
    depth = std::min(depth, A.col(j).dot(ha) + hb[j] - std::abs(tb[j]));
    if (depth <= enough) return depth;
  }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double sine = std::sqrt(std::max(0.0, 1.0 - C(i, j) * C(i, j)));
      if (sine < 1e-6) continue;
      const double ra = ha[i1] * A(i2, j) + ha[i2] * A(i1, j);
      const double rb = hb[j1] * A(i, j2) + hb[j2] * A(i, j1);
      const double gap = std::abs(t[i2] * C(i1, j) - t[i1] * C(i2, j));
      depth = std::min(depth, (ra + rb - gap) / sine);
      if (depth <= enough) return depth;
    }
  }
  return depth;
}

}  // namespace tumble
