#include "manifold_record.hpp"

namespace tumble {

ManifoldRecord record_manifold(const BoxManifold& m, const BodyState& a, const BodyState& b) {
  ManifoldRecord r;
  r.offset = a.R.transpose() * (b.x - a.x);
  r.turn = a.R.transpose() * b.R;
  r.normal = a.R.transpose() * m.normal;
  r.count = m.count;
  for (int i = 0; i < m.count; ++i) {
    const ManifoldPoint& p = m.points[i];
    const Vec3 half = (0.5 * p.separation) * m.normal;  // position is midway between the two
    r.on_a[i] = a.R.transpose() * (p.position - half - a.x);
    r.on_b[i] = b.R.transpose() * (p.position + half - b.x);
    r.id[i] = p.id;
  }
  return r;
}

bool recycle_manifold(const ManifoldRecord& record, const BodyState& a, double ra,
                      const BodyState& b, double rb, BoxManifold& out) {
  const Vec3 offset = a.R.transpose() * (b.x - a.x);
  if ((offset - record.offset).cwiseAbs().maxCoeff() > kRecycleDistance) return false;
  // Each column of R_aᵀ R_b against the record's: the turn's largest change, rad.
  const double bound = kRecycleDistance / (ra + rb);
  for (int j = 0; j < 3; ++j) {
    const Vec3 column = a.R.transpose() * b.R.col(j);
    if ((column - record.turn.col(j)).cwiseAbs().maxCoeff() > bound) return false;
  }
  out.normal = a.R * record.normal;
  out.count = record.count;
  for (int i = 0; i < record.count; ++i) {
    const Vec3 qa = a.x + a.R * record.on_a[i];
    const Vec3 qb = b.x + b.R * record.on_b[i];
    ManifoldPoint& p = out.points[i];
    p.position = 0.5 * (qa + qb);
    p.separation = (qb - qa).dot(out.normal);
    p.id = record.id[i];
  }
  return true;
}

}  // namespace tumble
