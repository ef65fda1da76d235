/// Shock propagation: the contact solver's last velocity pass, from the ground up.
#include <algorithm>

#include "solver.hpp"

namespace tumble {

// Shock propagation (Guendelman, Bridson & Fedkiw 2003, §7): after the iterations, one sweep
// over the bodies from the ground up in which each body's supports count as immovable, so it
// alone takes whatever approach the unconverged iterations left. A stack then cannot sink
// however tall it is, even on the first step before warm starting has built its impulses, and
// a heavy body on a light one cannot crush it. The sweep only pushes (never pulls) and only
// where a contact still approaches, so an impact already resolved exactly, or a scene without
// gravity (no "up"), is untouched.
//
// A body's support contacts are solved together, as one active-set solve over all their
// points (they share a normal when the body rests flat on several others). Solved one after
// another, each pushed the body up at one side and tipped it; the next support then had to
// push the other side up further, and the body left faster than every support under it. Up a
// 100-row pyramid that ratchet added up to 0.7 m/s at the top in the first step and threw the
// upper rows off.
//
// The impulses of the sweep join the points' accumulated normal impulses, so they warm start
// the next step: the iterations then begin from a support that already holds the stack up,
// and the friction bound μ Σλₙ of each patch covers the load it carries. Kept out of the
// totals, the sweep's share had to be found again every step, the iterations never held a tall
// stack, and pyramid_large (5,050 boxes) crept sideways until it fell; with them it stands
// (its top box moves 4.3 mm) and sleeps within 2 s.
//
// The sweep is ordered, but a body's solve depends only on the earlier solves that share one
// of its bodies: each solve's wave is one more than the latest wave of its bodies, and the
// solves of one wave touch disjoint bodies. Waves run in turn, each shared among the pool's
// threads, and a solve starts once its bodies' earlier solves are done (their turns): every
// body sees the same updates in the same order as in the ordered sweep.
void Solver::shock_propagation(std::span<Contact> contacts, const Vec3& gravity, double dt,
                               WorkerPool& pool, BesideJob beside) {
  auto alone = [&] { if (beside.run) beside.run(beside.arg); };  // no pass to share it with
  const double g = gravity.norm();
  if (g == 0.0) return alone();
  const Vec3 up = -gravity / g;
  if (!shock_plan_.ready) {
    supports_.resize(contacts.size());
    pool.for_each(contacts.size(), 64, [&](std::size_t begin, std::size_t end) {
      find_supports(contacts, up, begin, end);
    });
    order_shock_propagation(pool.size() > 1);
  }
  const std::size_t groups = shock_plan_.groups;
  if (pool.size() == 1 || groups == 0) {  // the height order itself: what the waves replay
    for (std::size_t gi = 0; gi < groups; ++gi) push_up_body(contacts, group(gi), up, dt);
    return alone();
  }
  push_up_in_waves(contacts, up, dt, pool, beside, shock_plan_.last_wave);
}

// Nothing in the order reads a velocity: it is the supports' geometry at the step start. On
// several threads it is found beside the velocity sweeps (solve_contacts), where it was a
// serial stretch of ~60 µs of `pile`'s step (the entries written on the other core, read back
// one line at a time), during which the other thread waited.
void Solver::plan_shock_propagation(std::span<const Contact> contacts, const Vec3& gravity) {
  const double g = gravity.norm();
  if (g == 0.0) return;
  supports_.resize(contacts.size());
  find_supports(contacts, -gravity / g, 0, contacts.size());
  order_shock_propagation(true);
}

void Solver::order_shock_propagation(bool waves) {
  shock_plan_.groups = order_supports_by_height();
  if (waves && shock_plan_.groups > 0) {
    shock_plan_.last_wave = number_waves(shock_plan_.groups);
    order_groups_by_wave(shock_plan_.groups, shock_plan_.last_wave);
  }
  shock_plan_.ready = true;
}

// A contact whose normal is nearly horizontal supports nothing and is left to the iterations,
// as is one that would hold the floor up (gravity pointing away from it): the floor does not
// move, and the body under it has no support to be pushed from. Each contact's entry (with its
// lower body's solver index, for the waves) is found on the pool, or on one thread beside the
// velocity sweeps: on the owner's thread alone, while the other threads waited, this read
// every ~1 KB contact, a cache miss each. With the bucket sort of order_supports_by_height,
// the pass's serial part in `pile` on two threads went from ~124 to ~81 µs a step (the same
// bits).
void Solver::find_supports(std::span<const Contact> contacts, const Vec3& up, std::size_t begin,
                           std::size_t end) {
  constexpr double kSupportCosine = 0.3;  // |n·up| below this: a side contact (> 72° from up)
  std::vector<SupportEntry>& found = supports_;
  for (std::size_t i = begin; i < end; ++i) {
    const Contact& c = contacts[i];
    const std::uint32_t upper = upper_of(c, up);
    found[i].upper = kStaticBody;
    if (std::abs(c.normal.dot(up)) < kSupportCosine || upper == kStaticBody) continue;
    const std::uint32_t lower = c.a == upper ? c.b : c.a;
    found[i] = {up.dot(bodies_[upper].s.x), upper, static_cast<std::uint32_t>(i),
                lower == kStaticBody ? -1 : index_[lower], 0};
  }
}

// By the height of the supported body (then its id), its contacts together in contact order,
// each body a group: the entries are put in buckets by body (a counting sort, which keeps
// contact order), and only the bodies are sorted, by (height, solver index; solver bodies
// ascend by id). Sorting the ~1,400 entries of `pile` themselves took ~70 µs a step; the ~900
// bodies' keys and the buckets take ~50.
std::size_t Solver::order_supports_by_height() {
  std::vector<SupportEntry>& found = supports_;
  std::vector<std::uint32_t>& start = support_start_;  // per solver body: its bucket
  std::vector<std::pair<double, std::uint32_t>>& keys = support_keys_;
  start.assign(sb_.size() + 1, 0);
  keys.clear();
  for (const SupportEntry& e : found) {
    if (e.upper == kStaticBody) continue;
    const auto u = static_cast<std::uint32_t>(index_[e.upper]);
    if (start[u + 1]++ == 0) keys.emplace_back(e.height, u);
  }
  for (std::size_t u = 1; u < start.size(); ++u) start[u] += start[u - 1];
  std::vector<SupportEntry>& order = order_;  // (height, body held up, contact)
  order.resize(start.back());
  for (const SupportEntry& e : found)
    if (e.upper != kStaticBody) order[start[index_[e.upper]]++] = e;  // start[u]: u's end
  std::sort(keys.begin(), keys.end());
  found.resize(order.size());
  group_start_.clear();
  std::uint32_t at = 0;
  for (const auto& key : keys) {
    group_start_.push_back(at);
    const std::uint32_t u = key.second;
    for (std::uint32_t i = u == 0 ? 0 : start[u - 1]; i < start[u]; ++i) found[at++] = order[i];
  }
  const std::size_t groups = group_start_.size();
  group_start_.push_back(at);
  std::swap(found, order);
  return groups;
}

std::span<const SupportEntry> Solver::group(std::size_t gi) const {
  return {order_.data() + group_start_[gi], order_.data() + group_start_[gi + 1]};
}

// Each solve's wave, and its turn at each body it touches (the body it holds up, and those
// under it): how many solves before it in height order touch that body.
std::uint32_t Solver::number_waves(std::size_t groups) {
  waves_.assign(sb_.size(), 0);
  touches_.assign(sb_.size(), 0);
  wave_of_.resize(groups);
  upper_turn_.resize(groups);
  std::uint32_t last = 0;
  for (std::size_t gi = 0; gi < groups; ++gi) {
    const std::int32_t upper = index_[order_[group_start_[gi]].upper];
    std::uint32_t wave = waves_[upper];
    for (std::uint32_t k = group_start_[gi]; k < group_start_[gi + 1]; ++k) {
      const std::int32_t lower = order_[k].lower;
      if (lower >= 0) wave = std::max(wave, waves_[lower]);
    }
    ++wave;
    waves_[upper] = wave;
    upper_turn_[gi] = touches_[upper]++;
    for (std::uint32_t k = group_start_[gi]; k < group_start_[gi + 1]; ++k) {
      SupportEntry& e = order_[k];
      if (e.lower < 0) continue;
      waves_[e.lower] = wave;
      e.lower_turn = touches_[e.lower]++;
    }
    wave_of_[gi] = wave;
    last = std::max(last, wave);
  }
  return last;
}

// A counting sort of the groups by wave (stable: height order within a wave); wave_start_[w]
// is where wave w begins in wave_order_.
void Solver::order_groups_by_wave(std::size_t groups, std::uint32_t last) {
  wave_start_.assign(last + 2, 0);
  for (std::uint32_t w : wave_of_) ++wave_start_[w + 1];
  for (std::size_t w = 1; w < wave_start_.size(); ++w) wave_start_[w] += wave_start_[w - 1];
  wave_order_.resize(groups);
  for (std::size_t gi = 0; gi < groups; ++gi)
    wave_order_[wave_start_[wave_of_[gi]]++] = static_cast<std::uint32_t>(gi);
  for (std::size_t w = wave_start_.size() - 1; w > 0; --w) wave_start_[w] = wave_start_[w - 1];
  wave_start_[0] = 0;
}

// Waves 1 … last are the phases of one job (pool.for_each_phase) without barriers, as the
// solver's sweeps run (contact_passes.cpp): a solve waits only for its own bodies' earlier
// solves. A barrier per wave held both threads for the slowest chunk of each of `pile`'s
// waves. The turns count on from the solve's sweeps (turn_base_), as theirs do. The job
// beside, if any, is phase 0, a single chunk: the thread that takes it meets the waves once it
// is done and takes the chunks left, each waiting for its bodies' turns like any other.
void Solver::push_up_in_waves(std::span<Contact> contacts, const Vec3& up, double dt,
                              WorkerPool& pool, BesideJob beside, std::uint32_t last) {
  auto solve_in_turn = [&](std::size_t gi) {
    const std::span<const SupportEntry> supports = group(gi);
    const std::int32_t u = index_[supports[0].upper];
    SolverBody& upper = sb_[u];
    pool.wait_turn(upper.turn, turn_base_[u] + upper_turn_[gi]);
    for (const SupportEntry& e : supports)
      if (e.lower >= 0) pool.wait_turn(sb_[e.lower].turn, turn_base_[e.lower] + e.lower_turn);
    push_up_body(contacts, supports, up, dt);
    pass_turn(upper.turn);
    for (const SupportEntry& e : supports)
      if (e.lower >= 0) pass_turn(sb_[e.lower].turn);
  };
  const std::size_t first = beside.run ? 1 : 0;  // phases before the first wave's
  pool.for_each_phase(
      first + last, 4,
      [&](std::size_t p) {
        return p < first ? 1 : wave_start_[p - first + 2] - wave_start_[p - first + 1];
      },
      [&](std::size_t p, std::size_t from, std::size_t to) {
        if (p < first) return beside.run(beside.arg);
        const std::size_t begin = wave_start_[p - first + 1];
        for (std::size_t k = begin + from; k < begin + to; ++k) solve_in_turn(wave_order_[k]);
      },
      false);
  for (std::size_t k = 0; k < sb_.size(); ++k) turn_base_[k] += touches_[k];
}

/// Shock propagation of one body on its supports (`group`: (height, contact) entries whose
/// contacts all hold the body up): the supports held fixed, the body alone takes the approach
/// the iterations left, over all the points at once when they share a normal (else contact by
/// contact, as when they do not fit one solve).
void Solver::push_up_body(std::span<Contact> contacts,
                          std::span<const SupportEntry> group, const Vec3& up, double dt) {
  constexpr double kParallel = 1.0 - 1e-9;  // cosine between normals solved as one
  const Contact& first = contacts[group[0].contact];
  const Vec3 n = first.normal.dot(up) > 0.0 ? first.normal : Vec3(-first.normal);
  int m = 0;
  bool together = group.size() > 1;
  for (const SupportEntry& e : group) {
    const Contact& c = contacts[e.contact];
    m += c.count;
    together = together && std::abs(c.normal.dot(n)) >= kParallel;
  }
  if (!together || m > kMaxActiveSetPoints) {
    for (const SupportEntry& e : group) push_up(contacts[e.contact], up, dt);
    return;
  }
  const std::uint32_t id = group[0].upper;
  SolverBody* upper = body(id);
  std::array<Vec3, kMaxActiveSetPoints> r;  // points from the body's centre, m
  std::array<ContactPoint*, kMaxActiveSetPoints> points{};
  PointVector vn(m), target(m);
  bool approaching = false;
  int k = 0;
  for (const SupportEntry& e : group) {
    Contact& c = contacts[e.contact];
    const bool upper_is_b = c.b == id;
    const SolverBody* support = body(upper_is_b ? c.a : c.b);
    for (int q = 0; q < c.count; ++q, ++k) {
      ContactPoint& p = c.points[q];
      points[k] = &p;
      r[k] = upper_is_b ? p.rb : p.ra;
      const Vec3 rs = upper_is_b ? p.ra : p.rb;
      vn(k) = (point_velocity(upper, r[k]) - point_velocity(support, rs)).dot(n);
      target(k) = target_of(p, dt);
      approaching = approaching || vn(k) < target(k) - 1e-9;
    }
  }
  if (!approaching) return;
  Vec3 origin = Vec3::Zero();
  for (int q = 0; q < m; ++q) origin += r[q];
  origin /= m;
  std::array<Vec3, kMaxActiveSetPoints> offsets;
  for (int q = 0; q < m; ++q) offsets[q] = r[q] - origin;
  Vec3 t1, t2;
  tangents(n, t1, t2);
  const ContactSide side{upper->inv_mass, upper->inv_inertia, origin};
  const NormalSystem sys = make_normal_system(n, t1, t2, offsets.data(), m, nullptr, &side);
  ActiveSetCache cache(sys);  // keeps a reference to sys
  const PointVector impulse = solve_active_set(cache, vn, target);
  for (int q = 0; q < m; ++q) {
    if (impulse(q) <= 0.0) continue;
    apply(nullptr, upper, Vec3::Zero(), r[q], impulse(q) * n);
    points[q]->normal_impulse += impulse(q);  // warm starts the next step (see above)
  }
}

/// One contact of shock propagation: the lower body held fixed, the upper one alone takes the
/// approach the iterations left.
void Solver::push_up(Contact& c, const Vec3& up, double dt) {
  const bool a_lower = c.normal.dot(up) > 0.0;
  SolverBody* a = a_lower ? nullptr : body(c.a);
  SolverBody* b = a_lower ? body(c.b) : nullptr;
  const int n = c.count;
  PointVector vn(n), target(n);
  bool approaching = false;
  for (int k = 0; k < n; ++k) {
    const ContactPoint& p = c.points[k];
    vn(k) = (point_velocity(body(c.b), p.rb) - point_velocity(body(c.a), p.ra)).dot(c.normal);
    target(k) = target_of(p, dt);
    approaching = approaching || vn(k) < target(k) - 1e-9;
  }
  if (!approaching) return;
  const NormalSystem sys = normal_system_of(c, a, b);
  ActiveSetCache cache(sys);
  const PointVector impulse = solve_active_set(cache, vn, target);
  for (int k = 0; k < n; ++k) {
    if (impulse(k) <= 0.0) continue;
    apply(a, b, c.points[k].ra, c.points[k].rb, impulse(k) * c.normal);
    c.points[k].normal_impulse += impulse(k);  // warm starts the next step
  }
}

}  // namespace tumble
