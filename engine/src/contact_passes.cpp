/// The passes of the contact solve (solve_contacts, contact_solver.hpp) in their order, and
/// how each pass's sweeps are shared among the pool's threads: in contact order on one
/// thread, colour by colour on several, with the same bits. The per-contact work of each pass
/// is Solver's (contact_solver.cpp, contact_rows.cpp, shock_propagation.cpp).
#include <atomic>
#include <functional>

#include "contact_solver.hpp"
#include "solver.hpp"
#include "worker_pool.hpp"

namespace tumble {

namespace {

// Colours of under kShared contacts on average (`pyramid`: ~10) leave each thread a chunk or
// two per colour, whose waits cost more than the second thread saves: such a solve runs on
// the owner's thread in contact order.
constexpr std::size_t kShared = 24;

/// Whether pass `pass` of `passes` runs backward: the first of several with `first_backward`.
bool runs_backward(bool first_backward, int passes, int pass) {
  return first_backward && passes > 1 && pass == 0;
}

/// Runs fn(contact, slot) over the contacts `passes` times on this thread, in contact order
/// (the first pass backward with `first_backward` and several passes): the order a coloured
/// sweep replays, without the colours' waits. slot(i) names contact i's rows.
template <typename Fn, typename Slot = std::identity>
void sweep_in_order(std::span<Contact> contacts, Fn&& fn, int passes, bool first_backward,
                    Slot slot = {}) {
  for (int pass = 0; pass < passes; ++pass) {
    if (runs_backward(first_backward, passes, pass)) {
      for (std::size_t i = contacts.size(); i-- > 0;) fn(contacts[i], slot(i));
      continue;
    }
    for (std::size_t i = 0; i < contacts.size(); ++i) fn(contacts[i], slot(i));
  }
}

/// Runs fn(contact, slot) over the contacts `passes` times (slot: the contact's rows, in sweep
/// order), colour by colour when the solve has colours, each colour
/// shared among the pool's threads (its contacts touch disjoint bodies). All the passes' colours
/// are the phases of one job: `pile`'s ~40 colours × 12 velocity iterations were ~500 jobs a
/// step, whose publication and idle chunks took as long as the second thread saved.
///
/// The phases have no barrier between them: a contact waits only for its own bodies' earlier
/// contacts, counted per body (SolverBody::turn against its rank, pass after pass), and a
/// thread that finds a colour's chunks all taken starts on the next colour at once. A barrier
/// per colour made each thread wait for the slowest chunk of every colour, ~0.5 µs of each
/// colour's ~2 µs in `pile`. Each body still meets its contacts in contact order, so the
/// result is the one-thread sweep's, bit for bit. No deadlock: a thread takes a chunk of a
/// colour only once every chunk of the colours before is taken, so the chunk in progress of
/// the lowest colour waits on nothing unfinished.
///
/// With `first_backward` the first of several passes runs the other way: the colours from
/// the last, each body's contacts from its last (its rank counted down), so one thread and
/// several still give the same bits. Why: contact order puts the floor's contacts first and
/// goes up the stacks, so a forward pass carries the support up a column in one sweep, but a
/// change at the top (a warm-started load that no longer fits) reaches the floor only one
/// level a sweep. One backward pass first hands the loads down the stacks once; the forward
/// passes then carry the support back up. It is symmetric Gauss–Seidel's first half only:
/// alternating every pass undid part of each forward pass's support, and a tower's floor load
/// converged more slowly (docs/engine-log.md, "Sweeps both ways"). With it ten sweeps hold the
/// 5,050-box pyramid better than twelve forward did (top box 1.05 mm against 1.93 mm); nine
/// let it fall.
///
/// `beside` (if any) runs once, as a phase of one chunk before the first colour: the thread
/// that takes it joins the sweeps where the others have got to (as shock propagation's
/// BesideJob). It must read and write nothing the sweeps do.
template <typename Fn>
void sweep(SolverScratch& scratch, std::span<Contact> contacts, WorkerPool& pool, Fn&& fn,
           int passes = 1, bool first_backward = false, BesideJob beside = {}) {
  constexpr std::size_t kGrain = 8;  // contacts per chunk: 0.1–0.5 µs each
  auto backward = [&](int pass) { return runs_backward(first_backward, passes, pass); };
  ContactColours& colours = scratch.colours;
  if (pool.size() == 1 || colours.count() == 0) {
    if (beside.run) beside.run(beside.arg);
    return sweep_in_order(contacts, fn, passes, first_backward);
  }
  const std::size_t first = beside.run ? 1 : 0;  // phases before the first colour's
  const std::size_t count = colours.count();
  const std::span<SolverBody> sb(scratch.bodies);
  // The turns go on counting from the solve's earlier passes (turn_base): zeroing them here,
  // on the owner's thread, pulled every body's line from the core that last wrote it (~40 µs
  // of `pile`'s step on two threads, in five passes, while the other thread waited).
  const std::span<const std::uint32_t> base(scratch.turn_base);
  pool.for_each_phase(
      first + count * static_cast<std::size_t>(passes), kGrain,
      [&](std::size_t p) {
        if (p < first) return std::size_t{1};
        const std::size_t phase = p - first;
        const bool back = backward(static_cast<int>(phase / count));
        return colours.of(back ? count - 1 - phase % count : phase % count).size();
      },
      [&](std::size_t p, std::size_t begin, std::size_t end) {
        if (p < first) return beside.run(beside.arg);
        const std::size_t phase = p - first;
        const auto pass = static_cast<std::uint32_t>(phase / count);
        const bool back = backward(static_cast<int>(pass));
        const std::size_t colour = back ? count - 1 - phase % count : phase % count;
        const std::size_t start = colours.offset[colour];
        auto rank = [&](std::int32_t body, std::uint32_t r) {
          return base[body] + pass * colours.degree[body] +
                 (back ? colours.degree[body] - 1 - r : r);
        };
        for (std::size_t slot = start + begin; slot < start + end; ++slot) {
          const std::uint32_t k = colours.order[slot];
          const std::int32_t a = scratch.colour_a[k], b = scratch.colour_b[k];
          if (a >= 0) pool.wait_turn(sb[a].turn, rank(a, colours.rank_a[k]));
          if (b >= 0) pool.wait_turn(sb[b].turn, rank(b, colours.rank_b[k]));
          fn(contacts[k], slot);
          if (a >= 0) pass_turn(sb[a].turn);
          if (b >= 0) pass_turn(sb[b].turn);
        }
      },
      false);
  for (std::size_t i = 0; i < sb.size(); ++i)
    scratch.turn_base[i] += static_cast<std::uint32_t>(passes) * colours.degree[i];
}

/// Shock propagation with the split impulse beside it: once shock propagation has found its
/// order and waves, one thread runs the whole split impulse while the other starts the waves,
/// and the first joins the waves where they have got to once it is done (BesideJob,
/// solver.hpp). Neither pass reads what the other writes: shock propagation moves the
/// velocities (v, w) and the normal impulses, the split impulse only the pseudo velocities
/// (vp, wp) and its own impulses, from rows fixed before the sweeps. The split impulse runs in
/// contact order, as on one thread, and shock propagation's solves wait for their bodies'
/// turns as before, so the bits are one thread's. Why: shared between two threads with a
/// wait per body, the split impulse's cheap contacts gained only 1.2× from the second thread
/// (`pile`: 159 → 126 µs a step), shock propagation 1.5× (263 → 171). Side by side the two
/// take 258–266 µs instead of 297–301 (the split impulse itself ~200 µs beside shock
/// propagation, which leaves its thread little of shock propagation to join). Two threads
/// only: on many, the split impulse on one thread could outlast shock propagation.
template <typename Fn>
void shock_beside_split(Solver& solver, SolverScratch& scratch, std::span<Contact> contacts,
                        const Vec3& gravity, double dt, const SolverSettings& settings,
                        WorkerPool& pool, Fn& split_impulse) {
  const ContactColours& colours = scratch.colours;
  scratch.slot_of.resize(contacts.size());
  for (std::size_t slot = 0; slot < colours.order.size(); ++slot)
    scratch.slot_of[colours.order[slot]] = static_cast<std::uint32_t>(slot);
  auto split = [&] {
    sweep_in_order(contacts, split_impulse, settings.position_iterations,
                   settings.first_sweep_backward,
                   [&](std::size_t i) { return std::size_t{scratch.slot_of[i]}; });
  };
  using Split = decltype(split);
  solver.shock_propagation(contacts, gravity, dt, pool,
                           {[](void* job) { (*static_cast<Split*>(job))(); }, &split});
}

/// True when some point of contact c penetrates deeper than `slop` (m).
bool deeper_than(const Contact& c, double slop) {
  for (int i = 0; i < c.count; ++i)
    if (-c.points[i].separation > slop) return true;
  return false;
}

/// On several threads, the colours the sweeps share the contacts by (scratch.colours; none on
/// one thread, or when the colours are too small to share: the sweeps then go in contact
/// order). Each contact's two solver bodies are read on the pool: a contact is ~1 KB, and on
/// the owner's thread alone this read missed the cache once per contact.
void colour_for_threads(std::span<const Contact> contacts, std::size_t body_count,
                        SolverScratch& scratch, WorkerPool& pool) {
  ContactColours& colours = scratch.colours;
  colours.offset.clear();
  if (pool.size() == 1) return;
  scratch.colour_a.resize(contacts.size());
  scratch.colour_b.resize(contacts.size());
  pool.for_each(contacts.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      scratch.colour_a[i] = contacts[i].a == kStaticBody ? -1 : scratch.index[contacts[i].a];
      scratch.colour_b[i] = scratch.index[contacts[i].b];
    }
  });
  colour_contacts(scratch.colour_a, scratch.colour_b, body_count, colours);
  if (contacts.size() < kShared * colours.count()) colours.offset.clear();
}

/// The contact the sweeps meet `slot`-th: colour by colour when there are colours, else in
/// contact order.
std::size_t contact_in_slot(const ContactColours& colours, std::size_t slot) {
  return colours.count() > 0 ? colours.order[slot] : slot;
}

/// Every contact's rows (Solver::prepare), slot k holding the contact the sweeps meet k-th:
/// colour by colour, else contact order. Returns whether any point is deeper than the slop,
/// found while each contact is in cache (the separations are the step start's and the solve
/// does not change them).
bool prepare_rows(Solver& solver, std::span<Contact> contacts, double dt,
                  const SolverSettings& settings, SolverScratch& scratch, WorkerPool& pool) {
  if (scratch.rows.size() < contacts.size()) scratch.rows.resize(contacts.size());
  if (scratch.point_rows.size() < contacts.size()) scratch.point_rows.resize(contacts.size());
  if (scratch.impulses.size() < contacts.size()) scratch.impulses.resize(contacts.size());
  std::atomic<bool> deep{false};
  pool.for_each(contacts.size(), 32, [&](std::size_t begin, std::size_t end) {
    bool any = false;
    for (std::size_t slot = begin; slot < end; ++slot) {
      Contact& c = contacts[contact_in_slot(scratch.colours, slot)];
      solver.prepare(c, slot, dt, settings);
      any = any || deeper_than(c, settings.slop);
    }
    if (any) deep.store(true, std::memory_order_relaxed);
  });
  return deep.load(std::memory_order_relaxed);
}

}  // namespace

// The velocities of the bodies in contact, in the order of Guendelman, Bridson & Fedkiw 2003:
// gravity, the collision pass (impacts with restitution), the contact pass (sequential
// impulses, e = 0); positions then follow in flight with the corrected velocities
// (semi-implicit Euler), the split-impulse pseudo velocities added to the positions only.
// On several threads every pass but shock propagation (ordered by height, in waves) sweeps the
// contacts colour by colour, which replays the sweep in contact order that one thread runs.
int solve_contacts(std::span<Body> bodies, std::span<const std::uint32_t> solver_bodies,
                   std::span<Contact> contacts, const Vec3& gravity, double dt,
                   const SolverSettings& settings, SolverScratch& scratch, WorkerPool& pool,
                   PassClock& clock) {
  constexpr std::size_t kBodyGrain = 128;
  Solver solver(bodies, solver_bodies, scratch, pool, dt * gravity);
  colour_for_threads(contacts, solver_bodies.size(), scratch, pool);
  clock.lap(SolvePass::setup);
  const ContactColours& colours = scratch.colours;
  const bool coloured = colours.count() > 0;
  const bool deep = prepare_rows(solver, contacts, dt, settings, scratch, pool);
  clock.lap(SolvePass::rows);
  std::atomic<int> impacts{0};
  sweep(scratch, contacts, pool, [&](Contact& c, std::size_t slot) {
    if (solver.impact(c, slot, gravity, dt)) impacts.fetch_add(1, std::memory_order_relaxed);
  });
  clock.lap(SolvePass::impacts);
  sweep(scratch, contacts, pool, [&](Contact&, std::size_t slot) { solver.warm_start(slot); });
  clock.lap(SolvePass::warm_start);
  // On several threads shock propagation's order is found beside the sweeps (one thread takes
  // it, then joins them): it was a serial stretch of its own.
  auto plan = [&] { solver.plan_shock_propagation(contacts, gravity); };
  using Plan = decltype(plan);
  const BesideJob plan_beside{[](void* job) { (*static_cast<Plan*>(job))(); }, &plan};
  sweep(scratch, contacts, pool, [&](Contact&, std::size_t slot) { solver.solve_velocity(slot); },
        settings.velocity_iterations, settings.first_sweep_backward,
        settings.shock_propagation && coloured ? plan_beside : BesideJob{});
  // Shock propagation and the next step's warm start read the impulses in the contacts.
  pool.for_each(contacts.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t slot = begin; slot < end; ++slot)
      solver.store_impulses(contacts[contact_in_slot(colours, slot)], slot);
  });
  clock.lap(SolvePass::velocity);
  // The split impulse starts from zero pseudo velocities and only pushes: while no point is
  // deeper than the slop every target is ≤ 0 and every sweep would leave all of them zero (a
  // resting stack: `pyramid` spent 6 % of its instructions proving that).
  const bool split = deep && settings.position_iterations > 0;
  auto split_impulse = [&](Contact&, std::size_t slot) { solver.solve_position(slot); };
  if (settings.shock_propagation && split && pool.size() == 2 && coloured) {
    shock_beside_split(solver, scratch, contacts, gravity, dt, settings, pool, split_impulse);
    clock.lap(SolvePass::shock_propagation);  // both passes, side by side
  } else {
    if (settings.shock_propagation) solver.shock_propagation(contacts, gravity, dt, pool);
    clock.lap(SolvePass::shock_propagation);
    if (split)
      sweep(scratch, contacts, pool, split_impulse, settings.position_iterations,
            settings.first_sweep_backward);
  }
  clock.lap(SolvePass::split_impulse);
  pool.for_each(solver_bodies.size(), kBodyGrain,
                [&](std::size_t begin, std::size_t end) { solver.finish(begin, end); });
  solver.release();
  clock.lap(SolvePass::finish);
  return impacts.load();
}

}  // namespace tumble
