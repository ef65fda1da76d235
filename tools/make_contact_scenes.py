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


def pile(n_side=10, layers=10, seed=7):
    rng = random.Random(seed)
    bodies = []
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
                q = quat_from_axis_angle(axis, rng.uniform(0, math.pi))
                bodies.append(box(f"b{len(bodies)}", size, mass, pos,
                                  COLORS[len(bodies) % len(COLORS)],
                                  orientation=[round(v, 9) for v in q],
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
