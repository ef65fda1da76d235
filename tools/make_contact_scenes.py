#!/usr/bin/env python3
"""Writes the box-contact scenes (tower, pyramid, pyramid_large, pile, heavy_on_light, dominoes)
into scenes/.

Run from the repository root: python3 tools/make_contact_scenes.py
The pile uses a fixed seed, so the files are reproducible.
"""
import json
import math
import random
from pathlib import Path

SCENES = Path(__file__).resolve().parent.parent / "scenes"
COLORS = ["#d9822b", "#2a9d8f", "#e9c46a", "#e76f51", "#264653", "#8ab17d", "#b56576"]


def scene(name, description, bodies, floor=(0.0, 0.6), dt=1.0 / 60.0):
    return {
        "name": name,
        "description": description,
        "gravity": [0, -9.81, 0],
        "floor": {"height": 0, "restitution": floor[0], "friction": floor[1]},
        "dt": dt, "integrator": "exact", "toi": "root", "toi_tolerance": 1e-9,
        "bodies": bodies,
    }


def box(name, size, mass, position, color, **extra):
    b = {"name": name, "size": size, "mass": mass,
         "position": [round(v, 6) for v in position], "color": color}
    b.update(extra)
    return b


def tower():
    bodies = [box(f"box{i}", [1, 1, 1], 1, [0, 0.5 + i, 0], COLORS[i % len(COLORS)])
              for i in range(10)]
    return scene("tower", "Ten unit cubes stacked exactly on each other (e = 0, mu = 0.6): the "
                 "tower must stand still without sinking or drifting, then sleep.", bodies)


def pyramid(base=20, gap=0.05, mass=1, name="pyramid"):
    """A 2-D pyramid in the x–y plane: row r holds base − r unit cubes, centres 1 + gap apart
    (so neighbours in a row never touch), resting exactly on the row below (y = 0.5 + r)."""
    bodies = []
    for row in range(base):
        for i in range(base - row):
            x = (i - 0.5 * (base - row - 1)) * (1 + gap)
            bodies.append(box(f"r{row}b{i}", [1, 1, 1], mass, [x, 0.5 + row, 0],
                              COLORS[row % len(COLORS)]))
    heavy = "" if mass == 1 else f"{mass} kg each, "
    return scene(name, f"A 2D pyramid of unit cubes with a base of {base} "
                 f"({len(bodies)} boxes, {heavy}{round(gap * 100)} cm gaps within a row; "
                 "e = 0, mu = 0.6): it must stand and fall asleep.", bodies)


def pyramid_large():
    """The base-100 version of `pyramid` (5,050 boxes of 100 kg): the large stack of issue 11."""
    return pyramid(base=100, mass=100, name="pyramid_large")


def quat_from_axis_angle(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    s = math.sin(angle / 2) / n
    return [math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s]


def rotation_columns(q):
    """The body axes in the world (columns of the rotation) of unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)],
            [2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)],
            [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]]


def box_separation(a, b):
    """Signed distance of boxes a and b, each (centre, axes, half extents): the largest
    separation over the 15 separating axes (< 0: minus their overlap depth), the test
    `tumble-bench contact` measures penetration with (bench/contact/penetration.cpp)."""
    (ca, ra, ha), (cb, rb, hb) = a, b
    dot = lambda u, v: sum(p * q for p, q in zip(u, v))
    d = [q - p for p, q in zip(ca, cb)]
    axes = ra + rb + [[u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]] for u in ra for v in rb]
    best = -math.inf
    for axis in axes:
        n = math.sqrt(dot(axis, axis))
        if n < 1e-6:
            continue
        u = [c / n for c in axis]
        reach = (sum(h * abs(dot(e, u)) for e, h in zip(ra, ha)) +
                 sum(h * abs(dot(e, u)) for e, h in zip(rb, hb)))
        best = max(best, abs(dot(d, u)) - reach)
    return best


def pile(n_side=10, layers=10, seed=7, clearance=0.01):
    """Boxes of random size and pose on a grid. A box that its random turn would leave closer
    than `clearance` (m) to a box already placed (some did overlap by up to 10 cm) is turned
    again with draws from a second generator, so every other box keeps its draws."""
    rng = random.Random(seed)
    again = random.Random(seed + 1)
    bodies, placed = [], []
    spacing = 0.8
    for layer in range(layers):
        for i in range(n_side):
            for k in range(n_side):
                size = [round(rng.uniform(0.35, 0.6), 3) for _ in range(3)]
                mass = round(500 * size[0] * size[1] * size[2], 3)  # 500 kg/m³
                pos = [(i - (n_side - 1) / 2) * spacing + rng.uniform(-0.05, 0.05),
                       1.0 + layer * spacing,
                       (k - (n_side - 1) / 2) * spacing + rng.uniform(-0.05, 0.05)]
                axis = [rng.uniform(-1, 1) for _ in range(3)]
                q = [round(v, 9) for v in quat_from_axis_angle(axis, rng.uniform(0, math.pi))]
                half = [h / 2 for h in size]
                centre = [round(v, 6) for v in pos]
                near = [p for p in placed
                        if math.dist(p[0], centre) <
                        math.hypot(*half) + math.hypot(*p[2]) + clearance]
                while any(box_separation((centre, rotation_columns(q), half), p) < clearance
                          for p in near):
                    axis = [again.uniform(-1, 1) for _ in range(3)]
                    q = [round(v, 9) for v in quat_from_axis_angle(axis, again.uniform(0, math.pi))]
                placed.append((centre, rotation_columns(q), half))
                bodies.append(box(f"b{len(bodies)}", size, mass, pos,
                                  COLORS[len(bodies) % len(COLORS)],
                                  orientation=q,
                                  velocity=[round(rng.uniform(-0.5, 0.5), 3), 0,
                                            round(rng.uniform(-0.5, 0.5), 3)]))
    return scene("pile", f"{len(bodies)} boxes of random size and pose dropped from a "
                 f"{n_side}x{n_side}x{layers} grid into a pile (e = 0.1, mu = 0.5).",
                 bodies, floor=(0.1, 0.5))


def heavy_on_light():
    bodies = [box("light", [1, 1, 1], 1, [0, 0.5, 0], "#2a9d8f"),
              box("heavy", [1.5, 1, 1.5], 100, [0, 1.5, 0], "#e76f51")]
    return scene("heavy_on_light", "A 100 kg box resting on a 1 kg box (mass ratio 100:1; "
                 "e = 0, mu = 0.6): the stack must hold.", bodies)


def dominoes(n=20):
    bodies = []
    for i in range(n):
        extra = {"angular_velocity": [0, 0, -1.5]} if i == 0 else {}
        bodies.append(box(f"d{i}", [0.2, 2, 1], 1, [i * 1.0, 1.0, 0],
                          COLORS[i % len(COLORS)], **extra))
    return scene("dominoes", f"A row of {n} dominoes (0.2 x 2 x 1 m, 1 m apart; e = 0, "
                 "mu = 0.5); the first is tipped over and knocks down the rest.",
                 bodies, floor=(0.0, 0.5))


def main():
    for s in (tower(), pyramid(), pyramid_large(), pile(), heavy_on_light(), dominoes()):
        path = SCENES / f"{s['name']}.json"
        text = json.dumps(s, indent=1)
        path.write_text(text + "\n")
        print(path, len(s["bodies"]), "bodies")


if __name__ == "__main__":
    main()
