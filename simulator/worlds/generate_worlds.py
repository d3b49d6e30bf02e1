#!/usr/bin/env python3
"""Writes the shipped cairn-sim worlds from one description of their geometry.

    python3 simulator/worlds/generate_worlds.py        # rewrites the files next to this script

Outputs (all in this folder):
  tunnel.xml, tunnel_lanes.yaml    the traversability lanes of seed 000 and their contract
  apartment.xml, apartment_places.yaml   the rooms of seed 001 and their polygons
  arena.xml                        rooms and clutter for 2-D occupancy mapping (seed 003)
  outdoor.xml, outdoor_terrain.bin heightfield terrain with slopes, rocks and structures
  terraces.xml, terraces_lanes.yaml  one-way drops and ditches in walled lanes (directed terrain)
  simple.xml, simple_terrain.bin   seed 002's simple environment: a house and a tree on a hill
  structured.xml                   seed 002's urban block: buildings, kerbs, parked cars, a passage
  unstructured.xml, unstructured_terrain.bin  seed 002's unstructured world: a canyon and a bridge
  floor.xml, rocks.xml, breakwater.xml, cave.xml  seed 004's underwater worlds (water as the
                                   medium): flat seabed, rocks, four columns, a U-shaped cave

Everything is deterministic (the outdoor and simple terrains use fixed seeds), so running it again
reproduces the committed files byte for byte.
"""

import math
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

WALL_RGBA = "0.62 0.6 0.56 1"
FLOOR_RGBA = "0.45 0.45 0.42 1"
FEATURE_RGBA = "0.7 0.55 0.35 1"
OBSTACLE_RGBA = "0.55 0.35 0.3 1"


def f(x):
    """Compact fixed-point number formatting for XML attributes."""
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def box(name, cx, cy, cz, hx, hy, hz, rgba=WALL_RGBA, euler=None, extra=""):
    e = f' euler="{f(euler[0])} {f(euler[1])} {f(euler[2])}"' if euler else ""
    return (f'    <geom name="{name}" type="box" size="{f(hx)} {f(hy)} {f(hz)}" '
            f'pos="{f(cx)} {f(cy)} {f(cz)}"{e} rgba="{rgba}"{extra}/>')


def aabb(name, x0, x1, y0, y1, z0, z1, rgba=WALL_RGBA):
    """A box given by its extent."""
    return box(name, (x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2,
               (x1 - x0) / 2, (y1 - y0) / 2, (z1 - z0) / 2, rgba)


def ramp(name, x0, z0, slope_deg, rise, y0, y1, rgba=FEATURE_RGBA, down=False):
    """A solid ramp whose top surface rises `rise` metres at `slope_deg` along +x from (x0, z0)
    (or falls, when down=True). The box is thick enough to reach below z0 everywhere, so it
    looks solid from every side. Returns (xml, horizontal length)."""
    a = math.radians(slope_deg)
    length = rise / math.tan(a)
    half_thick = rise / 2 / math.cos(a) + 0.1
    sign = -1.0 if down else 1.0
    # Midpoint of the top surface, then down along the surface normal by half the thickness.
    mx, mz = x0 + length / 2, z0 + (rise / 2 if not down else rise / 2)
    if down:
        mz = z0 - rise / 2
    nx, nz = -sign * math.sin(a), math.cos(a)
    cx, cz = mx - nx * half_thick, mz - nz * half_thick
    xml = box(name, cx, (y0 + y1) / 2, cz, length / 2 / math.cos(a), (y1 - y0) / 2, half_thick,
              rgba, euler=(0, -sign * slope_deg, 0))
    return xml, length


def header(model, comment, extra_option=""):
    return [f"<!-- {comment} -->",
            f'<mujoco model="{model}">',
            '  <compiler angle="degree"/>',
            f'  <option timestep="0.002"{extra_option}/>',
            '  <visual><global offwidth="1280" offheight="720"/></visual>']


# --------------------------------------------------------------------------------------------
# tunnel

LANE_WIDTH = 4.0
WALL_T = 0.2
WALL_H = 1.5
LANE_X0 = 3.0     # lanes start here; x in [0, 3] is the shared cross corridor
LANE_X1 = 24.0    # end wall face
FEATURE_X = 8.0   # most features start here
START_X = 4.0


def lane_y(k):
    return k * LANE_WIDTH + LANE_WIDTH / 2


def lane_walls(n_lanes):
    """The outer walls of `n_lanes` lanes and the walls between them (from the cross corridor to
    the end wall), shared by the lane worlds."""
    y_max = n_lanes * LANE_WIDTH
    walls = [
        aabb("wall_start", -WALL_T, 0.0, -WALL_T / 2, y_max + WALL_T / 2, -0.3, WALL_H),
        aabb("wall_end", LANE_X1, LANE_X1 + WALL_T, -WALL_T / 2, y_max + WALL_T / 2, -0.3, WALL_H),
        aabb("wall_south", -WALL_T, LANE_X1 + WALL_T, -WALL_T / 2, WALL_T / 2, -0.3, WALL_H),
        aabb("wall_north", -WALL_T, LANE_X1 + WALL_T, y_max - WALL_T / 2, y_max + WALL_T / 2,
             -0.3, WALL_H)]
    for k in range(1, n_lanes):
        y = k * LANE_WIDTH
        walls.append(aabb(f"wall_lane_{k}", LANE_X0, LANE_X1, y - WALL_T / 2, y + WALL_T / 2,
                          -0.3, WALL_H))
    return walls


def tunnel():
    lanes = []   # (name, description, feature lines, start, goal, notes)
    geoms = []
    n_lanes = 10
    y_max = n_lanes * LANE_WIDTH
    # Floor: a plane 0.3 m down (the trench bottom) under decks whose top is z = 0.
    geoms.append('    <geom name="ground" type="plane" size="60 60 0.1" pos="12 20 -0.3" '
                 f'rgba="{FLOOR_RGBA}"/>')
    trench_lane = 7
    ty0, ty1 = trench_lane * LANE_WIDTH, (trench_lane + 1) * LANE_WIDTH
    trench_x0, trench_x1 = 10.0, 10.6
    geoms.append(aabb("deck_south", -1, 25, -1, ty0, -0.3, 0.0, FLOOR_RGBA))
    geoms.append(aabb("deck_trench_near", -1, trench_x0, ty0, ty1, -0.3, 0.0, FLOOR_RGBA))
    geoms.append(aabb("deck_trench_far", trench_x1, 25, ty0, ty1, -0.3, 0.0, FLOOR_RGBA))
    geoms.append(aabb("deck_north", -1, 25, ty1, y_max + 1, -0.3, 0.0, FLOOR_RGBA))
    # Walls: outer box and the walls between lanes (from the cross corridor to the end wall).
    geoms += lane_walls(n_lanes)

    def inner(k):
        return k * LANE_WIDTH + WALL_T / 2, (k + 1) * LANE_WIDTH - WALL_T / 2

    # Lane 0: 1 m cube.
    k = 0
    yc = lane_y(k)
    geoms.append(aabb("cube", 9.0, 10.0, yc - 0.5, yc + 0.5, 0.0, 1.0, OBSTACLE_RGBA))
    lanes.append(dict(lane=k, name="cube", experiment="seed 000 exp 1",
                      feature="1 x 1 x 1 m cube, x 9.0..10.0, y %s..%s, z 0..1" % (f(yc - .5), f(yc + .5)),
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.0,
                      traversable_pioneer3at=True,
                      note="the cube is an obstacle; 1.4 m free on either side of it"))

    # Lane 1: 5 deg ramp to a 0.3 m platform.
    k = 1
    yc = lane_y(k)
    y0, y1 = inner(k)
    xml, length = ramp("ramp5", FEATURE_X, 0.0, 5.0, 0.3, y0, y1)
    geoms.append(xml)
    geoms.append(aabb("ramp5_platform", FEATURE_X + length, LANE_X1, y0, y1, 0.0, 0.3, FEATURE_RGBA))
    lanes.append(dict(lane=k, name="ramp_5deg", experiment="seed 000 exp 2",
                      feature="5 deg ramp x 8.0..%s rising 0 -> 0.3 m, then a 0.3 m platform to "
                              "the end wall, wall to wall" % f(FEATURE_X + length),
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.3,
                      traversable_pioneer3at=True, note="goal on the platform"))

    # Lane 2: 10 deg ramp to a 0.3 m platform (the only way onto it).
    k = 2
    yc = lane_y(k)
    y0, y1 = inner(k)
    xml, length = ramp("ramp10", FEATURE_X, 0.0, 10.0, 0.3, y0, y1)
    geoms.append(xml)
    geoms.append(aabb("ramp10_platform", FEATURE_X + length, LANE_X1, y0, y1, 0.0, 0.3,
                      FEATURE_RGBA))
    lanes.append(dict(lane=k, name="ramp_10deg", experiment="seed 000 exp 3",
                      feature="10 deg ramp x 8.0..%s rising 0 -> 0.3 m, then a 0.3 m platform to "
                              "the end wall, wall to wall" % f(FEATURE_X + length),
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.3,
                      traversable_pioneer3at=False,
                      note="the platform is reachable only over the 10 deg ramp (its other edges "
                           "are lane walls); the P3-AT body can climb it, its profile forbids it"))

    # Lane 3: 5 deg then 11 deg ramp.
    k = 3
    yc = lane_y(k)
    y0, y1 = inner(k)
    rise5 = 2.0 * math.tan(math.radians(5.0))
    rise11 = 1.5 * math.tan(math.radians(11.0))
    xml, l5 = ramp("ramp5_11_lower", FEATURE_X, 0.0, 5.0, rise5, y0, y1)
    geoms.append(xml)
    xml, l11 = ramp("ramp5_11_upper", FEATURE_X + l5, rise5, 11.0, rise11, y0, y1)
    geoms.append(xml)
    top = rise5 + rise11
    geoms.append(aabb("ramp5_11_platform", FEATURE_X + l5 + l11, LANE_X1, y0, y1, 0.0, top,
                      FEATURE_RGBA))
    lanes.append(dict(lane=k, name="ramp_5_then_11deg", experiment="seed 000 exp 7",
                      feature="5 deg x 8.0..10.0 (0 -> %s m), 11 deg x 10.0..11.5 (-> %s m), "
                              "platform to the end wall" % (f(rise5), f(top)),
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=round(top, 4),
                      traversable_pioneer3at=False,
                      note="the 11 deg section is the IMU-compensation case"))

    # Lane 4: 1 cm step up.
    k = 4
    yc = lane_y(k)
    y0, y1 = inner(k)
    geoms.append(aabb("step1cm", 10.0, LANE_X1, y0, y1, 0.0, 0.01, FEATURE_RGBA))
    lanes.append(dict(lane=k, name="step_1cm", experiment="seed 000 exp 5",
                      feature="1 cm plate from x 10.0 to the end wall, wall to wall",
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.01,
                      traversable_pioneer3at=True, note=""))

    # Lane 5: 20 cm step up.
    k = 5
    yc = lane_y(k)
    y0, y1 = inner(k)
    geoms.append(aabb("step20cm", 10.0, LANE_X1, y0, y1, 0.0, 0.2, FEATURE_RGBA))
    lanes.append(dict(lane=k, name="step_20cm", experiment="seed 000 exp 6",
                      feature="20 cm block from x 10.0 to the end wall, wall to wall",
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.2,
                      traversable_pioneer3at=False,
                      note="the goal on top is unreachable; the P3-AT body cannot climb it"))

    # Lane 6: 5 deg ramp -> 0.2 m platform -> 20 cm drop.
    k = 6
    yc = lane_y(k)
    y0, y1 = inner(k)
    xml, length = ramp("drop_ramp", FEATURE_X, 0.0, 5.0, 0.2, y0, y1)
    geoms.append(xml)
    px0, px1 = FEATURE_X + length, FEATURE_X + length + 3.0
    geoms.append(aabb("drop_platform", px0, px1, y0, y1, 0.0, 0.2, FEATURE_RGBA))
    lanes.append(dict(lane=k, name="drop_20cm", experiment="seed 000 exp 4",
                      feature="5 deg ramp x 8.0..%s (0 -> 0.2 m), platform x %s..%s at 0.2 m, "
                              "20 cm drop at x %s, wall to wall" % (f(px0), f(px0), f(px1), f(px1)),
                      start=(START_X, yc, 0.0), goal=(17.0, yc, 0.0), goal_z=0.0,
                      traversable_pioneer3at=False,
                      note="the goal lies past the drop, which is the only way forward"))

    # Lane 7: trench.
    k = 7
    yc = lane_y(k)
    lanes.append(dict(lane=k, name="trench", experiment="derived (seed 000 section 7.3 #28)",
                      feature="trench x %s..%s (0.6 m wide), 0.3 m deep, wall to wall"
                              % (f(trench_x0), f(trench_x1)),
                      start=(START_X, yc, 0.0), goal=(14.0, yc, 0.0), goal_z=0.0,
                      traversable_pioneer3at=False, note="the bottom is the ground plane at -0.3"))

    # Lane 8: combined scene (20 cm step, 5 deg ramp, 1 cm step, 10 deg ramp).
    k = 8
    yc = lane_y(k)
    y0, y1 = inner(k)
    ymid = (y0 + y1) / 2
    geoms.append(aabb("combined_step20cm", 7.0, 8.5, y0, ymid, 0.0, 0.2, OBSTACLE_RGBA))
    xml, l_up = ramp("combined_ramp5_up", 10.0, 0.0, 5.0, 0.15, y0, y1)
    geoms.append(xml)
    geoms.append(aabb("combined_ramp5_top", 10.0 + l_up, 11.0 + l_up, y0, y1, 0.0, 0.15,
                      FEATURE_RGBA))
    xml, l_down = ramp("combined_ramp5_down", 11.0 + l_up, 0.15, 5.0, 0.15, y0, y1, down=True)
    geoms.append(xml)
    hump_end = 11.0 + l_up + l_down
    geoms.append(aabb("combined_step1cm", 15.5, LANE_X1, y0, y1, 0.0, 0.01, FEATURE_RGBA))
    xml, l10 = ramp("combined_ramp10", 17.5, 0.01, 10.0, 0.2, ymid, y1, OBSTACLE_RGBA)
    geoms.append(xml)
    geoms.append(aabb("combined_ramp10_platform", 17.5 + l10, 18.5 + l10, ymid, y1, 0.0, 0.21,
                      OBSTACLE_RGBA))
    lanes.append(dict(
        lane=k, name="combined", experiment="seed 000 exp 8",
        feature=("20 cm block x 7.0..8.5, y %s..%s (south half); 5 deg hump x 10.0..%s "
                 "(up to 0.15 m, 1 m flat, down), wall to wall; 1 cm plate from x 15.5 to the "
                 "end wall, wall to wall; 10 deg ramp x 17.5..%s (0.01 -> 0.21 m) and a 1 m "
                 "platform, y %s..%s (north half)")
        % (f(y0), f(ymid), f(hump_end), f(17.5 + l10), f(ymid), f(y1)),
        start=(START_X, yc, 0.0), goal=(21.5, yc, 0.0), goal_z=0.01,
        traversable_pioneer3at=True,
        note="pass the 20 cm block on its north side and the 10 deg ramp on its south side; "
             "crossing the hump and the 1 cm step is required"))

    # Lane 9: demo route: past the cube, over the 1 cm step and up a 5 deg ramp.
    k = 9
    yc = lane_y(k)
    y0, y1 = inner(k)
    geoms.append(aabb("demo_cube", 7.5, 8.5, y0, y0 + 1.0, 0.0, 1.0, OBSTACLE_RGBA))
    geoms.append(aabb("demo_step1cm", 11.0, LANE_X1, y0, y1, 0.0, 0.01, FEATURE_RGBA))
    xml, length = ramp("demo_ramp5", 14.0, 0.01, 5.0, 0.2, y0, y1)
    geoms.append(xml)
    geoms.append(aabb("demo_platform", 14.0 + length, LANE_X1, y0, y1, 0.0, 0.21, FEATURE_RGBA))
    lanes.append(dict(
        lane=k, name="demo", experiment="demo route",
        feature=("1 m cube x 7.5..8.5, y %s..%s (against the south wall); 1 cm plate from x "
                 "11.0; 5 deg ramp x 14.0..%s (0.01 -> 0.21 m); platform to the end wall")
        % (f(y0), f(y0 + 1.0), f(14.0 + length)),
        start=(START_X, yc, 0.0), goal=(21.0, yc, 0.0), goal_z=0.21,
        traversable_pioneer3at=True,
        note="every feature on the route is traversable for the pioneer3at profile"))

    lines = header("tunnel", "tunnel: the eight traversability experiments of seed 000 in walled "
                   "lanes, a combined scene and a demo route")
    lines += [
        "<!--",
        "  Generated by generate_worlds.py; coordinates and the lane contract are in",
        "  tunnel_lanes.yaml and README.md. Lanes run along +x, 4 m apart (lane k between walls",
        "  at y = 4k and 4k + 4), from a shared cross corridor (x 0..3) to the end wall at x = 24.",
        "  Floors are decks with their top at z = 0; the ground plane at z = -0.3 is the trench",
        "  bottom. Walls are 1.5 m high and 0.2 m thick.",
        "-->",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="12 20 30" dir="0 0 -1"/>',
    ]
    lines += geoms
    lines += ["  </worldbody>", "</mujoco>", ""]
    write("tunnel.xml", "\n".join(lines))

    # The lane contract.
    y = ["# Lanes of the tunnel world (generated by generate_worlds.py with tunnel.xml).",
         "# Poses are world frame: x_m, y_m, yaw_rad of the robot base. goal_z_m is the surface",
         "# height at the goal. traversable_pioneer3at: whether the pioneer3at profile may",
         "# reach the goal from the start.",
         "lanes:"]
    for lane in lanes:
        sx, sy, syaw = lane["start"]
        gx, gy, gyaw = lane["goal"]
        y += [f"  - lane: {lane['lane']}",
              f"    name: {lane['name']}",
              f"    experiment: \"{lane['experiment']}\"",
              f"    feature: \"{lane['feature']}\"",
              f"    start: {{x_m: {f(sx)}, y_m: {f(sy)}, yaw_rad: {f(syaw)}}}",
              f"    goal: {{x_m: {f(gx)}, y_m: {f(gy)}, yaw_rad: {f(gyaw)}}}",
              f"    goal_z_m: {f(lane['goal_z'])}",
              f"    traversable_pioneer3at: {'true' if lane['traversable_pioneer3at'] else 'false'}"]
        if lane["note"]:
            y.append(f"    note: \"{lane['note']}\"")
    write("tunnel_lanes.yaml", "\n".join(y) + "\n")
    return lanes


# --------------------------------------------------------------------------------------------
# apartment

def door(name, hinge_x, hinge_y, width, axis_dir, open_sign=1):
    """A hinged door leaf along +x (axis_dir 'x') or +y (axis_dir 'y') from its hinge, with a
    position actuator named like its joint. Returns (body xml, actuator xml)."""
    leaf = (f'<geom type="box" size="{f(width / 2 - 0.01)} 0.02 1.0" pos="{f(width / 2)} 0 1.01" '
            f'rgba="0.55 0.4 0.25 1" mass="15"/>')
    zrot = 0 if axis_dir == "x" else 90
    rng = "0 100" if open_sign > 0 else "-100 0"
    body = (f'    <body name="door_{name}_leaf" pos="{f(hinge_x)} {f(hinge_y)} 0" '
            f'euler="0 0 {zrot}">\n'
            f'      <joint name="door_{name}" type="hinge" axis="0 0 1" limited="true" '
            f'range="{rng}" damping="15"/>\n'
            f'      {leaf}\n'
            f'    </body>')
    act = (f'    <position name="door_{name}" joint="door_{name}" kp="60" forcelimited="true" '
           f'forcerange="-80 80"/>')
    return body, act


def furniture(name, parts, pos, yaw=0.0):
    """A mocap body (movable through SIM.CONTROL) made of boxes, cylinders and spheres.
    parts: list of (type, size, local pos, rgba)."""
    lines = [f'    <body name="{name}" mocap="true" pos="{f(pos[0])} {f(pos[1])} 0" '
             f'euler="0 0 {f(yaw)}">']
    for i, (typ, size, p, rgba) in enumerate(parts):
        lines.append(f'      <geom name="{name}_{i}" type="{typ}" size="{size}" '
                     f'pos="{f(p[0])} {f(p[1])} {f(p[2])}" rgba="{rgba}"/>')
    lines.append("    </body>")
    return "\n".join(lines)


def table_parts(lx, ly, h, leg_r, rgba="0.6 0.45 0.3 1"):
    parts = [("box", f"{f(lx / 2)} {f(ly / 2)} 0.02", (0, 0, h - 0.02), rgba)]
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(("cylinder", f"{f(leg_r)} {f((h - 0.04) / 2)}",
                          (sx * (lx / 2 - 0.05), sy * (ly / 2 - 0.05), (h - 0.04) / 2), rgba))
    return parts


def chair_parts(rgba="0.25 0.25 0.28 1"):
    parts = [("box", "0.21 0.21 0.015", (0, 0, 0.45), rgba),
             ("box", "0.015 0.21 0.22", (-0.2, 0, 0.69), rgba)]
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(("cylinder", "0.01 0.22", (sx * 0.18, sy * 0.18, 0.22), "0.7 0.7 0.72 1"))
    return parts


APARTMENT_ROOMS = [
    # name, polygon (x, y), seed 001 label value
    ("living_room", [(0.0, 0.0), (6.0, 0.0), (6.0, 4.5), (0.0, 4.5)], 45),
    ("kitchen", [(6.0, 0.0), (10.0, 0.0), (10.0, 4.5), (6.0, 4.5)], 60),
    ("corridor", [(0.0, 4.5), (10.0, 4.5), (10.0, 5.7), (0.0, 5.7)], 0),
    ("bedroom", [(0.0, 5.7), (6.0, 5.7), (6.0, 9.0), (0.0, 9.0)], 15),
    ("bathroom", [(6.0, 5.7), (10.0, 5.7), (10.0, 9.0), (6.0, 9.0)], 30),
]


def apartment():
    t = 0.15
    h = 2.4
    W, H = 10.0, 9.0
    g = ['    <geom name="floor" type="plane" size="15 15 0.1" pos="5 4.5 0" '
         f'rgba="{FLOOR_RGBA}"/>']
    # Outer walls.
    g.append(aabb("wall_south", -t, W + t, -t, 0, 0, h))
    g.append(aabb("wall_north", -t, W + t, H, H + t, 0, h))
    g.append(aabb("wall_west", -t, 0, 0, H, 0, h))
    g.append(aabb("wall_east", W, W + t, 0, H, 0, h))
    # Corridor walls (y = 4.5 and y = 5.7) with door openings 0.9 m wide.
    doors = []
    actuators = []

    def wall_with_openings(name, y0, openings):
        xs = [0.0] + [v for o in openings for v in o] + [W]
        for i in range(0, len(xs), 2):
            if xs[i + 1] - xs[i] > 1e-6:
                g.append(aabb(f"{name}_{i // 2}", xs[i], xs[i + 1], y0, y0 + t, 0, h))

    wall_with_openings("wall_corridor_south", 4.5 - t, [(2.0, 2.9), (7.5, 8.4)])
    wall_with_openings("wall_corridor_north", 5.7, [(2.0, 2.9), (7.5, 8.4)])
    # Living room / kitchen wall (x = 6) with an open passage y 1.0..2.2.
    g.append(aabb("wall_living_kitchen_0", 6.0 - t / 2, 6.0 + t / 2, 0.0, 1.0, 0, h))
    g.append(aabb("wall_living_kitchen_1", 6.0 - t / 2, 6.0 + t / 2, 2.2, 4.5 - t, 0, h))
    # Bedroom / bathroom wall (x = 6).
    g.append(aabb("wall_bedroom_bathroom", 6.0 - t / 2, 6.0 + t / 2, 5.7 + t, H, 0, h))
    # Doors: hinged at the west end of each opening, swinging into the rooms.
    for name, hx, hy, sign in [("living_room", 2.0, 4.5 - t / 2, -1),
                               ("kitchen", 7.5, 4.5 - t / 2, -1),
                               ("bedroom", 2.0, 5.7 + t / 2, 1),
                               ("bathroom", 7.5, 5.7 + t / 2, 1)]:
        body, act = door(name, hx, hy, 0.9, "x", sign)
        doors.append(body)
        actuators.append(act)
    # Fixed furniture.
    g.append(aabb("kitchen_counter", 9.35, 10.0, 0.0, 4.0, 0, 0.9, "0.8 0.8 0.78 1"))
    g.append(aabb("fridge", 6.2, 6.9, 3.6, 4.35, 0, 1.8, "0.9 0.9 0.92 1"))
    g.append(aabb("bed", 0.1, 2.1, 7.3, 8.95, 0, 0.5, "0.5 0.55 0.7 1"))
    g.append(aabb("wardrobe", 4.4, 5.9, 8.35, 8.95, 0, 2.0, "0.5 0.35 0.2 1"))
    g.append(aabb("nightstand", 2.2, 2.6, 8.5, 8.95, 0, 0.5, "0.5 0.35 0.2 1"))
    g.append(aabb("bathtub", 8.2, 9.95, 7.3, 8.95, 0, 0.55, "0.95 0.95 0.95 1"))
    g.append(aabb("washbasin", 6.2, 6.8, 8.4, 8.95, 0, 0.85, "0.95 0.95 0.95 1"))
    g.append(aabb("toilet", 9.3, 9.95, 6.0, 6.5, 0, 0.45, "0.95 0.95 0.95 1"))
    # Movable furniture (mocap bodies).
    movable = [
        furniture("sofa", [("box", "1.0 0.45 0.22", (0, 0, 0.22), "0.3 0.4 0.55 1"),
                           ("box", "1.0 0.1 0.2", (0, 0.35, 0.62), "0.3 0.4 0.55 1")],
                  (2.5, 0.6)),
        furniture("armchair", [("box", "0.4 0.4 0.22", (0, 0, 0.22), "0.55 0.3 0.3 1"),
                               ("box", "0.4 0.1 0.2", (0, 0.3, 0.62), "0.55 0.3 0.3 1")],
                  (5.0, 0.7)),
        furniture("coffee_table", table_parts(1.0, 0.5, 0.45, 0.02), (2.5, 1.8)),
        furniture("shelf", [("box", "0.6 0.18 0.9", (0, 0, 0.9), "0.6 0.45 0.3 1")], (0.8, 4.1)),
        furniture("kitchen_table", table_parts(1.2, 0.8, 0.75, 0.025), (7.8, 2.0)),
        furniture("chair_1", chair_parts(), (7.8, 1.3), 90),
        furniture("chair_2", chair_parts(), (7.8, 2.7), -90),
        furniture("glass", [("cylinder", "0.035 0.025", (0, 0, 0.025), "0.7 0.85 0.95 1")],
                  (4.2, 3.2)),
    ]
    lines = header("apartment", "apartment: the domestic rooms of seed 001 (living room, kitchen, "
                   "corridor, bedroom, bathroom) with doors and movable furniture")
    lines += [
        "<!--",
        "  Generated by generate_worlds.py. A 10 x 9 m flat: living room (x 0..6, y 0..4.5) and",
        "  kitchen (x 6..10, y 0..4.5) joined by an open passage (x = 6, y 1.0..2.2); corridor",
        "  (y 4.5..5.7); bedroom (x 0..6, y 5.7..9) and bathroom (x 6..10, y 5.7..9). Four",
        "  hinged doors 0.9 m wide (door_<room>) open from the corridor; cairn-sim opens them at",
        "  start and SIM.CONTROL opens and closes them. Movable furniture are mocap bodies",
        "  (sofa, armchair, coffee_table, shelf, kitchen_table, chair_1, chair_2, glass) that",
        "  SIM.CONTROL can move or remove. Room polygons: apartment_places.yaml.",
        "-->",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="5 4.5 10" dir="0 0 -1"/>',
    ]
    lines += g + doors + movable
    lines += ["  </worldbody>", "  <actuator>"] + actuators + ["  </actuator>"]
    # A leaf turns about the end of the wall it is hung on and always touches it there: without
    # these exclusions the contact pushes every door back to about 30 degrees, which leaves too
    # little of the opening for a robot.
    lines += ["  <contact>"] + [
        f'    <exclude body1="door_{name}_leaf" body2="world"/>'
        for name in ("living_room", "kitchen", "bedroom", "bathroom")] + ["  </contact>"]
    lines += ["</mujoco>", ""]
    write("apartment.xml", "\n".join(lines))

    y = ["# Semantic places of the apartment world (generated by generate_worlds.py):",
         "# room name, seed 001 label value and polygon (world frame, metres, counter-clockwise).",
         "places:"]
    for name, poly, value in APARTMENT_ROOMS:
        pts = ", ".join(f"[{f(x)}, {f(yv)}]" for x, yv in poly)
        y += [f"  - name: {name}", f"    label_value: {value}", f"    polygon: [{pts}]"]
    write("apartment_places.yaml", "\n".join(y) + "\n")


# --------------------------------------------------------------------------------------------
# arena

def arena():
    t = 0.15
    h = 1.0
    W, H = 12.0, 10.0
    g = ['    <geom name="floor" type="plane" size="15 15 0.1" pos="6 5 0" '
         f'rgba="{FLOOR_RGBA}"/>']
    g.append(aabb("wall_south", -t, W + t, -t, 0, 0, h))
    g.append(aabb("wall_north", -t, W + t, H, H + t, 0, h))
    g.append(aabb("wall_west", -t, 0, 0, H, 0, h))
    g.append(aabb("wall_east", W, W + t, 0, H, 0, h))
    # Wall at y = 6 with doorways x 2.5..3.5 and 8.5..9.5.
    g.append(aabb("wall_middle_0", 0, 2.5, 6.0, 6.0 + t, 0, h))
    g.append(aabb("wall_middle_1", 3.5, 8.5, 6.0, 6.0 + t, 0, h))
    g.append(aabb("wall_middle_2", 9.5, W, 6.0, 6.0 + t, 0, h))
    # Wall at x = 5 between the two upper rooms, with a doorway y 7.5..8.5.
    g.append(aabb("wall_upper_0", 5.0, 5.0 + t, 6.0 + t, 7.5, 0, h))
    g.append(aabb("wall_upper_1", 5.0, 5.0 + t, 8.5, H, 0, h))
    # A partial wall making an alcove in the lower right.
    g.append(aabb("wall_alcove", 8.0, 8.0 + t, 0.0, 3.0, 0, h))
    # Clutter: armchair at the bottom, balls, a chair in the upper-left room, a table upper right.
    # The balls (r 0.2 m) rise above the P3-DX's laser plane (0.30 m), as seed 003's map shows them.
    g.append(aabb("armchair_seat", 3.2, 4.2, 0.3, 1.1, 0, 0.45, "0.55 0.3 0.3 1"))
    g.append(aabb("armchair_back", 3.2, 4.2, 0.15, 0.3, 0, 0.9, "0.55 0.3 0.3 1"))
    g.append(aabb("armchair_arm_left", 3.05, 3.2, 0.15, 1.1, 0, 0.65, "0.55 0.3 0.3 1"))
    g.append(aabb("armchair_arm_right", 4.2, 4.35, 0.15, 1.1, 0, 0.65, "0.55 0.3 0.3 1"))
    balls = [(1.5, 2.5), (6.5, 1.2), (9.8, 4.5), (5.5, 4.2), (10.8, 1.0), (2.2, 4.8)]
    for i, (bx, by) in enumerate(balls):
        g.append(f'    <geom name="ball_{i}" type="sphere" size="0.2" pos="{f(bx)} {f(by)} 0.2" '
                 'rgba="0.85 0.6 0.1 1"/>')
    # Chair (thin legs) in the upper-left room, visible through the doorway at x 2.5..3.5.
    for i, (dx, dy) in enumerate([(-0.2, -0.2), (0.2, -0.2), (-0.2, 0.2), (0.2, 0.2)]):
        g.append(f'    <geom name="chair_leg_{i}" type="cylinder" size="0.015 0.225" '
                 f'pos="{f(3.0 + dx)} {f(8.5 + dy)} 0.225" rgba="0.7 0.7 0.72 1"/>')
    g.append(aabb("chair_seat", 2.75, 3.25, 8.25, 8.75, 0.45, 0.48, "0.3 0.3 0.35 1"))
    g.append(aabb("chair_back", 2.75, 3.25, 8.72, 8.75, 0.48, 0.9, "0.3 0.3 0.35 1"))
    # Table in the upper-right room.
    for i, (dx, dy) in enumerate([(-0.7, -0.4), (0.7, -0.4), (-0.7, 0.4), (0.7, 0.4)]):
        g.append(f'    <geom name="table_leg_{i}" type="cylinder" size="0.03 0.36" '
                 f'pos="{f(9.5 + dx)} {f(8.5 + dy)} 0.36" rgba="0.6 0.45 0.3 1"/>')
    g.append(aabb("table_top", 8.7, 10.3, 8.0, 9.0, 0.72, 0.76, "0.6 0.45 0.3 1"))
    lines = header("arena", "arena: rooms and clutter for 2-D occupancy mapping (seed 003): "
                   "armchair, balls, a chair seen through a doorway, a table")
    lines += [
        "<!--",
        "  Generated by generate_worlds.py. A 12 x 10 m area, walls 1 m high: the lower hall",
        "  (y 0..6) with an alcove (x 8..12, y 0..3 behind a wall at x = 8), a wall at y = 6 with",
        "  doorways at x 2.5..3.5 and 8.5..9.5, and two upper rooms split at x = 5 with a doorway",
        "  at y 7.5..8.5. Suggested start: (6, 3), facing +x.",
        "-->",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="6 5 10" dir="0 0 -1"/>',
    ]
    lines += g + ["  </worldbody>", "</mujoco>", ""]
    write("arena.xml", "\n".join(lines))


# --------------------------------------------------------------------------------------------
# room

def closed_room(name, W, H, summary, start):
    # A closed W x H m room (inside x 0..W, y 0..H), walls 1 m high and 0.15 m thick, nothing
    # else.
    t = 0.15
    h = 1.0
    g = [f'    <geom name="floor" type="plane" size="{W / 2 + 1:g} {H / 2 + 1:g} 0.1" '
         f'pos="{W / 2:g} {H / 2:g} 0" rgba="{FLOOR_RGBA}"/>']
    g.append(aabb("wall_south", -t, W + t, -t, 0, 0, h))
    g.append(aabb("wall_north", -t, W + t, H, H + t, 0, h))
    g.append(aabb("wall_west", -t, 0, 0, H, 0, h))
    g.append(aabb("wall_east", W, W + t, 0, H, 0, h))
    lines = header(name, summary)
    lines += [
        "<!--",
        f"  Generated by generate_worlds.py. Inside x 0..{W:g}, y 0..{H:g}; walls 1 m high, "
        "0.15 m thick.",
        f"  Suggested start: {start}.",
        "-->",
        "  <worldbody>",
        f'    <light name="sun" directional="true" pos="{W / 2:g} {H / 2:g} 10" dir="0 0 -1"/>',
    ]
    lines += g + ["  </worldbody>", "</mujoco>", ""]
    write(f"{name}.xml", "\n".join(lines))


def room():
    # Seed 003 test 34: a robot spinning at the room's centre sees every wall within 4.9 m.
    closed_room("room", 6.0, 4.0,
                "room: a closed 6 x 4 m room for the spin-in-place mapping test (seed 003)",
                "the centre (3, 2)")


def hall():
    # Seed 003 tests 35 and 36: a robot 1 m from the south wall at (8, 1) has its nearest other
    # wall 8 m away, beyond the 5.6 m laser: open floor where its beams return nothing.
    closed_room("hall", 16.0, 14.0,
                "hall: a closed 16 x 14 m hall for the no-return clearing and obstacle "
                "persistence tests (seed 003)",
                "(8, 1), 1 m from the south wall, facing north")


# --------------------------------------------------------------------------------------------
# outdoor

def outdoor():
    n = 121           # samples per side
    half = 30.0       # half size in metres: 0.5 m between samples
    rng = random.Random(2002)
    hills = [(-14, 12, 6.0, 1.6), (12, 15, 7.0, 2.2), (15, -12, 5.0, 1.2), (-12, -15, 8.0, 1.0)]
    heights = []
    for r in range(n):
        y = -half + 2 * half * r / (n - 1)
        row = []
        for c in range(n):
            x = -half + 2 * half * c / (n - 1)
            z = 0.0
            for hx, hy, sigma, amp in hills:
                z += amp * math.exp(-((x - hx) ** 2 + (y - hy) ** 2) / (2 * sigma ** 2))
            # A long even slope to the east (about 6 deg over x 18..28).
            if x > 18:
                z += min(x - 18, 10) * math.tan(math.radians(6.0))
            # Gentle roughness, flat around the start, fading in between 4 and 6 m from it (a hard
            # seam at 4 m left a 4 cm rise between two samples: a kerb nobody built).
            d = math.hypot(x, y)
            fade = min(1.0, max(0.0, (d - 4.0) / 2.0))
            fade = fade * fade * (3.0 - 2.0 * fade)
            z += fade * 0.04 * math.sin(0.9 * x + 0.3 * y) * math.cos(0.7 * y - 0.2 * x)
            row.append(z)
        heights.append(row)
    lo = min(min(row) for row in heights)
    hi = max(max(row) for row in heights)
    # MuJoCo's custom height-field format: int32 rows, int32 cols, float32 data, row 0 at -y.
    with open(os.path.join(HERE, "outdoor_terrain.bin"), "wb") as out:
        out.write(struct.pack("<ii", n, n))
        for row in heights:
            out.write(struct.pack(f"<{n}f", *row))
    g = ['    <geom name="terrain" type="hfield" hfield="terrain" pos="0 0 0" '
         'rgba="0.45 0.5 0.35 1"/>']
    # Rocks.
    for i in range(14):
        while True:
            x, y = rng.uniform(-26, 26), rng.uniform(-26, 26)
            if math.hypot(x, y) > 5:
                break
        s = rng.uniform(0.25, 0.8)
        g.append(f'    <geom name="rock_{i}" type="ellipsoid" size="{f(s)} {f(s * 0.8)} '
                 f'{f(s * 0.6)}" pos="{f(x)} {f(y)} {f(terrain_at(heights, n, half, x, y, lo))}" '
                 f'euler="0 0 {rng.randint(0, 179)}" rgba="0.5 0.48 0.45 1"/>')
    # A small house, a shed and a wall segment on flat-ish ground, plus trees.
    def on_ground(name, x0, x1, y0, y1, height, rgba=WALL_RGBA):
        z0 = min(terrain_at(heights, n, half, x, y, lo) for x in (x0, x1) for y in (y0, y1)) - 0.2
        return aabb(name, x0, x1, y0, y1, z0, z0 + 0.2 + height, rgba)
    g.append(on_ground("house_south", -4, 2, -10.2, -10.0, 2.5))
    g.append(on_ground("house_north", -4, 2, -6.2, -6.0, 2.5))
    g.append(on_ground("house_west", -4.2, -4, -10.2, -6.0, 2.5))
    g.append(on_ground("house_east_0", 2, 2.2, -10.2, -8.8, 2.5))
    g.append(on_ground("house_east_1", 2, 2.2, -7.6, -6.0, 2.5))
    g.append(on_ground("shed", 6, 8, 4, 6, 2.0, "0.55 0.4 0.3 1"))
    g.append(on_ground("garden_wall", -10, -2, 5, 5.3, 1.2))
    for i, (x, y) in enumerate([(4, 12), (-6, 18), (20, 2), (-20, -4), (10, -20)]):
        z = terrain_at(heights, n, half, x, y, lo)
        g.append(f'    <geom name="tree_{i}" type="cylinder" size="0.2 2.5" '
                 f'pos="{f(x)} {f(y)} {f(z + 2.3)}" rgba="0.4 0.3 0.2 1"/>')
    lines = header("outdoor", "outdoor: 60 x 60 m heightfield terrain with hills, a 6 deg "
                   "slope, rocks, a house, a shed, a garden wall and trees (seed 002)")
    lines += [
        "<!--",
        f"  Generated by generate_worlds.py. Terrain: outdoor_terrain.bin, {n} x {n} samples",
        f"  0.5 m apart over x, y in -30..30, heights {f(lo)}..{f(hi)} m (shifted so the lowest",
        "  point is z = 0). Flat start area around the origin; hills at (-14, 12), (12, 15),",
        "  (15, -12), (-12, -15); an even 6 deg slope rising east from x = 18 to 28.",
        "-->",
    ]
    lines += heightfield_body("outdoor_terrain.bin", half, hi - lo, g)
    write("outdoor.xml", "\n".join(lines))


# --------------------------------------------------------------------------------------------
# terraces

def terraces():
    """Directed terrain in walled lanes: one-way drops, a drop refused both ways, ditches of two
    widths, and a one-way drop with a ramp beside it. Same lane layout as the tunnel."""
    lanes = []
    geoms = []
    n_lanes = 5
    y_max = n_lanes * LANE_WIDTH
    geoms.append('    <geom name="ground" type="plane" size="40 40 0.1" pos="12 10 -0.3" '
                 f'rgba="{FLOOR_RGBA}"/>')

    def inner(k):
        return k * LANE_WIDTH + WALL_T / 2, (k + 1) * LANE_WIDTH - WALL_T / 2

    # Decks (top z = 0) everywhere but the ditches, which cut lanes 2 and 3 wall to wall.
    narrow = (10.0, 10.25, 0.08)  # x0, x1, depth: lane 2 (bottom seen by rings below 22 deg)
    wide = (10.0, 10.6, 0.25)     # lane 3
    cuts = {2: narrow, 3: wide}
    geoms.append(aabb("deck_start", -1, LANE_X0, -1, y_max + 1, -0.3, 0.0, FLOOR_RGBA))
    for k in range(n_lanes):
        y0, y1 = k * LANE_WIDTH, (k + 1) * LANE_WIDTH
        if k in cuts:
            x0, x1, depth = cuts[k]
            geoms.append(aabb(f"deck_{k}_near", LANE_X0, x0, y0, y1, -0.3, 0.0, FLOOR_RGBA))
            geoms.append(aabb(f"deck_{k}_far", x1, 25, y0, y1, -0.3, 0.0, FLOOR_RGBA))
            geoms.append(aabb(f"ditch_{k}_bottom", x0, x1, y0, y1, -0.3, -depth, FLOOR_RGBA))
        else:
            geoms.append(aabb(f"deck_{k}", LANE_X0, 25, y0, y1, -0.3, 0.0, FLOOR_RGBA))
    geoms += lane_walls(n_lanes)

    def terrace(k, name, rise, y0, y1, platform_x1):
        """A 5 deg ramp from x 8 up to `rise`, then a platform that ends in a drop."""
        xml, length = ramp(f"{name}_ramp", FEATURE_X, 0.0, 5.0, rise, y0, y1)
        geoms.append(xml)
        geoms.append(aabb(f"{name}_platform", FEATURE_X + length, platform_x1, y0, y1, 0.0, rise,
                          FEATURE_RGBA))
        return FEATURE_X + length

    # Lane 0: 8 cm one-way drop.
    k, yc = 0, lane_y(0)
    y0, y1 = inner(k)
    px0 = terrace(k, "oneway8", 0.08, y0, y1, 12.0)
    lanes.append(dict(
        lane=k, name="oneway_drop_8cm",
        feature="5 deg ramp x 8.0..%s (0 -> 0.08 m), platform to x 12.0, 8 cm drop at x 12.0, "
                "wall to wall" % f(px0),
        start=(START_X, yc, 0.0), goal=(15.0, yc, 0.0),
        pioneer3at="forward only: up the ramp and off the drop (8 cm <= 10 cm down); never "
                   "back (8 cm > 3 cm up), and there is no other way"))
    # Lane 1: 12 cm drop.
    k, yc = 1, lane_y(1)
    y0, y1 = inner(k)
    px0 = terrace(k, "drop12", 0.12, y0, y1, 12.0)
    lanes.append(dict(
        lane=k, name="drop_12cm",
        feature="5 deg ramp x 8.0..%s (0 -> 0.12 m), platform to x 12.0, 12 cm drop at x 12.0, "
                "wall to wall" % f(px0),
        start=(START_X, yc, 0.0), goal=(15.0, yc, 0.0),
        pioneer3at="neither way (12 cm > 10 cm down and > 3 cm up)"))
    # Lanes 2 and 3: ditches.
    for k, (x0, x1, depth), name in ((2, narrow, "ditch_narrow"), (3, wide, "ditch_wide")):
        yc = lane_y(k)
        lanes.append(dict(
            lane=k, name=name,
            feature="ditch x %s..%s (%s m wide), %s m deep, wall to wall"
                    % (f(x0), f(x1), f(x1 - x0), f(depth)),
            start=(START_X, yc, 0.0), goal=(15.0, yc, 0.0),
            pioneer3at="no (its ditch width is 0.10 m); rover (0.30 m): %s"
                       % ("yes" if x1 - x0 <= 0.30 else "no")))
    # Lane 4: 8 cm one-way drop on the south half, a 5 deg ramp down on the north half.
    k, yc = 4, lane_y(4)
    y0, y1 = inner(k)
    ymid = (y0 + y1) / 2
    px0 = terrace(k, "bypass", 0.08, y0, y1, 12.0)
    xml, length = ramp("bypass_ramp_down", 12.0, 0.08, 5.0, 0.08, ymid, y1, FEATURE_RGBA,
                       down=True)
    geoms.append(xml)
    lanes.append(dict(
        lane=k, name="oneway_drop_with_ramp",
        feature="5 deg ramp x 8.0..%s (0 -> 0.08 m), platform to x 12.0; at x 12.0 an 8 cm drop "
                "on y %s..%s and a 5 deg ramp down x 12.0..%s on y %s..%s"
                % (f(px0), f(y0), f(ymid), f(12.0 + length), f(ymid), f(y1)),
        start=(15.0, yc, math.pi), goal=(START_X, yc, math.pi),
        pioneer3at="yes, but only up the ramp on the north half (the drop is a step up this "
                   "way)"))

    lines = header("terraces", "terraces: one-way drops, a 12 cm drop, two ditches and a one-way "
                   "drop beside a ramp, in walled lanes")
    lines += [
        "<!--",
        "  Generated by generate_worlds.py; the lane contract is in terraces_lanes.yaml and",
        "  README.md. Same layout as the tunnel: lanes along +x, 4 m apart, from a cross",
        "  corridor (x 0..3) to the end wall at x = 24. Decks have their top at z = 0.",
        "-->",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="12 10 30" dir="0 0 -1"/>',
    ]
    lines += geoms + ["  </worldbody>", "</mujoco>", ""]
    write("terraces.xml", "\n".join(lines))
    y = ["# Lanes of the terraces world (generated by generate_worlds.py with terraces.xml).",
         "# Poses are world frame: x_m, y_m, yaw_rad of the robot base.",
         "lanes:"]
    for lane in lanes:
        sx, sy, syaw = lane["start"]
        gx, gy, gyaw = lane["goal"]
        y += [f"  - lane: {lane['lane']}",
              f"    name: {lane['name']}",
              f"    feature: \"{lane['feature']}\"",
              f"    start: {{x_m: {f(sx)}, y_m: {f(sy)}, yaw_rad: {f(syaw)}}}",
              f"    goal: {{x_m: {f(gx)}, y_m: {f(gy)}, yaw_rad: {f(gyaw)}}}",
              f"    pioneer3at: \"{lane['pioneer3at']}\""]
    write("terraces_lanes.yaml", "\n".join(y) + "\n")


# --------------------------------------------------------------------------------------------
# simple

SIMPLE_WORK_AREA = (-12.0, 14.0, -10.0, 12.0)   # x0, x1, y0, y1: seed 002's red rectangle
SIMPLE_HOUSE = (2.0, 10.0, 2.0, 8.0)            # x0, x1, y0, y1
SIMPLE_TREE = (-6.0, -4.0)


def smoothstep(t):
    t = min(1.0, max(0.0, t))
    return t * t * (3.0 - 2.0 * t)


def max_slope_deg(heights, n, half, skip):
    """The steepest triangle of the height field (either diagonal of each cell), in degrees,
    leaving out cells that touch the rectangle `skip` (x0, x1, y0, y1)."""
    step = 2 * half / (n - 1)
    worst = 0.0
    for r in range(n - 1):
        y = -half + step * r
        for c in range(n - 1):
            x = -half + step * c
            if x + step >= skip[0] and x <= skip[1] and y + step >= skip[2] and y <= skip[3]:
                continue
            z00, z10 = heights[r][c], heights[r][c + 1]
            z01, z11 = heights[r + 1][c], heights[r + 1][c + 1]
            for gx, gy in ((z10 - z00, z01 - z00), (z11 - z01, z11 - z10),
                           (z10 - z00, z11 - z10), (z11 - z01, z01 - z00)):
                worst = max(worst, math.degrees(math.atan(math.hypot(gx, gy) / step)))
    return worst


def gable_roof(name, x0, x1, y0, y1, z, pitch_deg, rgba):
    """A solid gable roof on the flat top (height z) of the box x0..x1, y0..y1, its ridge along x
    over the middle: two slabs thick enough to fill the attic down to z (no ray gets in under
    them) whose undersides stay inside the box."""
    a = math.radians(pitch_deg)
    w = (y1 - y0) / 2
    t = w * math.sin(a) + 0.05
    ym = (y0 + y1) / 2
    geoms = []
    for side, sign in (("south", 1.0), ("north", -1.0)):
        # Midpoint of the top surface, then down along the surface normal by half the thickness.
        my, mz = ym - sign * w / 2, z + w * math.tan(a) / 2
        ny, nz = -sign * math.sin(a), math.cos(a)
        geoms.append(box(f"{name}_{side}", (x0 + x1) / 2, my - ny * t / 2, mz - nz * t / 2,
                         (x1 - x0) / 2, w / math.cos(a) / 2, t / 2, rgba,
                         euler=(sign * pitch_deg, 0, 0)))
    return geoms, w * math.tan(a)


def simple():
    """Seed 002's simple environment (section 6.2.1): a house and a tree on a gently irregular
    hill, explored inside a rectangle."""
    n = 81            # samples per side
    half = 20.0       # half size in metres: 0.5 m between samples
    rng = random.Random(2024)
    # The hill: a ridge whose flat crest (1.3 m high, 3 m wide) runs from (-3, -2) past the start
    # to the house, so that both stand on it; random bumps make it irregular, faded out near the
    # start.
    p0, p1, amp, sigma, crest = (-3.0, -2.0), (8.0, 6.0), 1.3, 7.0, 1.5
    bumps = [(rng.uniform(-19, 19), rng.uniform(-19, 19), rng.uniform(-0.25, 0.25),
              rng.uniform(3.0, 5.0)) for _ in range(10)]
    ex, ey = p1[0] - p0[0], p1[1] - p0[1]
    heights = []
    for r in range(n):
        y = -half + 2 * half * r / (n - 1)
        row = []
        for c in range(n):
            x = -half + 2 * half * c / (n - 1)
            t = max(0.0, min(1.0, ((x - p0[0]) * ex + (y - p0[1]) * ey) / (ex * ex + ey * ey)))
            d = math.hypot(x - p0[0] - t * ex, y - p0[1] - t * ey)
            z = amp * math.exp(-max(0.0, d - crest) ** 2 / (2 * sigma ** 2))
            u = sum(a * math.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * s ** 2))
                    for bx, by, a, s in bumps)
            z += smoothstep((math.hypot(x, y) - 2.0) / 3.0) * u
            row.append(z)
        heights.append(row)
    lo = min(min(row) for row in heights)
    hi = max(max(row) for row in heights)
    hx0, hx1, hy0, hy1 = SIMPLE_HOUSE
    slope = max_slope_deg(heights, n, half, SIMPLE_HOUSE)
    assert slope <= 8.0, f"simple: the terrain is {slope:.2f} deg steep somewhere"
    with open(os.path.join(HERE, "simple_terrain.bin"), "wb") as out:
        out.write(struct.pack("<ii", n, n))
        for row in heights:
            out.write(struct.pack(f"<{n}f", *row))

    def ground_min(xs, ys):
        return min(terrain_at(heights, n, half, x, y, lo) for x in xs for y in ys)

    g = ['    <geom name="terrain" type="hfield" hfield="terrain" pos="0 0 0" '
         'rgba="0.45 0.5 0.35 1"/>']
    # The house: one solid box, sunk 0.2 m below its lowest corner, 3 m walls above it, and a
    # 25 deg gable roof.
    steps = [k * 0.5 for k in range(int(round((hx1 - hx0) / 0.5)) + 1)]
    house_z0 = ground_min([hx0 + s for s in steps], [hy0 + s for s in steps if s <= hy1 - hy0])
    wall_top = house_z0 + 3.0
    g.append(aabb("house", hx0, hx1, hy0, hy1, house_z0 - 0.2, wall_top))
    roof, ridge = gable_roof("house_roof", hx0, hx1, hy0, hy1, wall_top, 25.0, "0.6 0.3 0.25 1")
    g += roof
    # The tree: a trunk 2.5 m above the ground (sunk 0.2 m) under a crown 1.5 m in radius.
    tx, ty = SIMPLE_TREE
    tree_z0 = ground_min((tx - 0.25, tx + 0.25), (ty - 0.25, ty + 0.25))
    g.append(f'    <geom name="tree_trunk" type="cylinder" size="0.25 1.35" '
             f'pos="{f(tx)} {f(ty)} {f(tree_z0 + 1.15)}" rgba="0.4 0.3 0.2 1"/>')
    g.append(f'    <geom name="tree_crown" type="sphere" size="1.5" '
             f'pos="{f(tx)} {f(ty)} {f(tree_z0 + 3.7)}" rgba="0.25 0.45 0.2 1"/>')
    wx0, wx1, wy0, wy1 = SIMPLE_WORK_AREA
    lines = header("simple", "simple: seed 002's simple environment, a house and a tree on a "
                   "gently irregular 40 x 40 m height-field hill (work area x -12..14, y -10..12)")
    lines += [
        "<!--",
        f"  Generated by generate_worlds.py. Terrain: simple_terrain.bin, {n} x {n} samples",
        f"  0.5 m apart over x, y in -20..20, heights {f(lo)}..{f(hi)} m (shifted so the lowest",
        "  point is z = 0): a ridge whose flat crest, 3 m wide, runs from (-3, -2) to (8, 6), and",
        "  random bumps (seed 2024) that fade out within 2..5 m of the origin; at most "
        f"{slope:.1f} deg",
        "  steep outside the house. Start: the origin (z = "
        f"{terrain_at(heights, n, half, 0.0, 0.0, lo):.2f}), on the crest, flat within 2 m.",
        f"  House: a solid box x {f(hx0)}..{f(hx1)}, y {f(hy0)}..{f(hy1)}, walls 3 m above its "
        f"lowest corner (top z = {wall_top:.2f}),",
        f"  a 25 deg gable roof with its ridge along x, {ridge:.2f} m high. Tree at "
        f"({f(tx)}, {f(ty)}): trunk r 0.25 m,",
        "  2.5 m high, crown r 1.5 m on top. Everything stands on the terrain.",
        f"  Work area (seed 002's red rectangle): x {f(wx0)}..{f(wx1)}, y {f(wy0)}..{f(wy1)}.",
        "-->",
    ]
    lines += heightfield_body("simple_terrain.bin", half, hi - lo, g)
    write("simple.xml", "\n".join(lines))


# --------------------------------------------------------------------------------------------
# structured

KERB_H = 0.12
KERB_W = 0.3
KERB_RGBA = "0.75 0.75 0.72 1"
BUILDING_RGBA = ["0.62 0.6 0.56 1", "0.7 0.62 0.52 1", "0.55 0.58 0.62 1"]
CAR_RGBA = ["0.7 0.15 0.12 1", "0.15 0.3 0.6 1", "0.85 0.85 0.82 1", "0.2 0.2 0.22 1",
            "0.2 0.5 0.3 1", "0.8 0.65 0.15 1"]


def kerb(name, x0, x1, y0, y1, gaps):
    """A kerb along x (when x1 - x0 > y1 - y0) or y, cut by `gaps` (from, to) along it."""
    along_x = x1 - x0 > y1 - y0
    a0, a1 = (x0, x1) if along_x else (y0, y1)
    cuts = [a0] + [v for gap in gaps for v in gap] + [a1]
    out = []
    for i in range(0, len(cuts), 2):
        s0, s1 = cuts[i], cuts[i + 1]
        if along_x:
            out.append(aabb(f"{name}_{i // 2}", s0, s1, y0, y1, 0.0, KERB_H, KERB_RGBA))
        else:
            out.append(aabb(f"{name}_{i // 2}", x0, x1, s0, s1, 0.0, KERB_H, KERB_RGBA))
    return out


def car(name, cx, cy, along_x, rgba):
    """A parked car: a 4.2 x 1.8 x 0.9 m body and a 2.2 x 1.6 m cabin on it (1.4 m high), the
    cabin a little behind the middle."""
    lx, ly = (2.1, 0.9) if along_x else (0.9, 2.1)
    cx2, cy2 = (cx - 0.2, cy) if along_x else (cx, cy - 0.2)
    clx, cly = (1.1, 0.8) if along_x else (0.8, 1.1)
    return [aabb(f"{name}_body", cx - lx, cx + lx, cy - ly, cy + ly, 0.0, 0.9, rgba),
            aabb(f"{name}_cabin", cx2 - clx, cx2 + clx, cy2 - cly, cy2 + cly, 0.9, 1.4,
                 "0.3 0.35 0.4 1")]


# name, x0, x1, y0, y1, height
STRUCTURED_BUILDINGS = [
    ("building_nw", -19.0, -12.5, 5.0, 13.0, 6.0),
    ("building_n", -2.5, 5.5, 5.0, 14.0, 8.0),
    ("building_ne", 8.0, 17.0, 5.0, 12.0, 5.0),
    ("building_sw", -19.0, -12.5, -14.0, -5.0, 4.5),
    ("building_s", -2.5, 4.5, -13.0, -5.0, 7.0),
    ("building_se", 13.5, 19.5, -13.0, -5.0, 6.0),
]
# name, centre x, y, along x
STRUCTURED_CARS = [
    ("car_0", -14.0, 2.4, True),
    ("car_1", 12.0, 2.4, True),
    ("car_2", 17.5, -2.4, True),
    ("car_3", -5.1, 10.0, False),
    ("car_4", -9.9, -13.0, False),
    ("car_5", 7.1, -16.0, False),
]


def structured():
    """Seed 002's structured (urban) environment (section 6.2.2): buildings, streets with kerbs
    and parked cars on flat ground, and a narrow passage between two buildings."""
    g = ['    <geom name="ground" type="plane" size="30 30 0.1" pos="0 0 0" '
         f'rgba="{FLOOR_RGBA}"/>']
    for i, (name, x0, x1, y0, y1, h) in enumerate(STRUCTURED_BUILDINGS):
        g.append(aabb(name, x0, x1, y0, y1, 0.0, h, BUILDING_RGBA[i % len(BUILDING_RGBA)]))
    # Streets: main (along x) y -3.5..3.5; west (along y) x -11..-4; south-east (along y, south
    # of the main street only) x 6..12. Kerbs stand just outside their edges, cut at the crossings
    # and by gaps where the pavements, the passage and the yards behind the buildings are reached.
    w = KERB_W
    g += kerb("kerb_main_n_w", -20.0, -11.0, 3.5, 3.5 + w, [(-18.5, -16.5)])
    g += kerb("kerb_main_n_e", -4.0, 20.0, 3.5, 3.5 + w, [(0.5, 2.5), (5.0, 8.5), (15.5, 17.5)])
    g += kerb("kerb_main_s_w", -20.0, -11.0, -3.5 - w, -3.5, [(-16.5, -14.5)])
    g += kerb("kerb_main_s_e0", -4.0, 6.0, -3.5 - w, -3.5, [(0.5, 2.5)])
    g += kerb("kerb_main_s_e1", 12.0, 20.0, -3.5 - w, -3.5, [(12.8, 14.8)])
    g += kerb("kerb_west_w_n", -11.0 - w, -11.0, 3.5, 20.0, [(8.0, 10.0)])
    g += kerb("kerb_west_w_s", -11.0 - w, -11.0, -20.0, -3.5, [(-10.0, -8.0)])
    g += kerb("kerb_west_e_n", -4.0, -4.0 + w, 3.5, 20.0, [(15.0, 17.0)])
    g += kerb("kerb_west_e_s", -4.0, -4.0 + w, -20.0, -3.5, [(-17.0, -15.0)])
    g += kerb("kerb_se_w", 6.0 - w, 6.0, -20.0, -3.5, [(-11.0, -9.0)])
    g += kerb("kerb_se_e", 12.0, 12.0 + w, -20.0, -3.5, [(-10.0, -8.0)])
    for i, (name, cx, cy, along_x) in enumerate(STRUCTURED_CARS):
        g += car(name, cx, cy, along_x, CAR_RGBA[i % len(CAR_RGBA)])
    lines = header("structured", "structured: seed 002's structured (urban) environment, a "
                   "40 x 40 m block on flat ground with six buildings, streets with kerbs and "
                   "parked cars, and a 2.5 m passage between two buildings")
    lines += [
        "<!--",
        "  Generated by generate_worlds.py. Ground plane z = 0. Streets: main x -20..20,",
        "  y -3.5..3.5; west x -11..-4, y -20..20; south-east x 6..12, y -20..-3.5. Kerbs 0.12 m",
        "  high, 0.3 m wide just outside the street edges, cut at the crossings and by 2 m gaps",
        "  (3.5 m at the passage). Buildings (x, y, height): nw -19..-12.5, 5..13, 6 m;",
        "  n -2.5..5.5, 5..14, 8 m; ne 8..17, 5..12, 5 m; sw -19..-12.5, -14..-5, 4.5 m;",
        "  s -2.5..4.5, -13..-5, 7 m; se 13.5..19.5, -13..-5, 6 m. Passage between n and ne:",
        "  x 5.5..8 (2.5 m), y 5..12. Six parked cars (4.2 x 1.8 x 1.4 m) along the kerbs.",
        "  Start: (0, 0) in the main street, facing +x. Work area: the block, x -20..20,",
        "  y -20..20.",
        "-->",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="0 0 40" dir="0.2 0.1 -1"/>',
    ]
    lines += g + ["  </worldbody>", "</mujoco>", ""]
    write("structured.xml", "\n".join(lines))


# --------------------------------------------------------------------------------------------
# unstructured

UNSTRUCTURED_WORK_AREA = (-18.0, 18.0, -18.0, 18.0)   # x0, x1, y0, y1
UNSTRUCTURED_START = (15.0, 15.0)                     # the top-right corner (seed 002 §6.2.3)
CANYON_X = (-4.0, 0.0)        # the canyon floor across x, for y from its ramp to its north end
CANYON_WALL_M = 1.0           # its walls rise from the floor's edge to the rims over this
CANYON_DEPTH = 2.2            # its floor below the rims' level (z 0 before the shift)
CANYON_Y = (-20.0, 14.0)      # south: open (its ramp), north: closed
CANYON_RAMP_Y = (-17.0, 0.0)  # the floor falls from the rim level to the depth along +y (7.4 deg)
BRANCH_X = (-16.0, -4.0)      # north of the bridge the canyon opens west into a basin, out of
BRANCH_Y = (10.5, 16.0)       # sight from above and from south of the bridge: only a robot that
                              # passes under the bridge sees it
BRIDGE_Y = (6.0, 9.0)         # the deck across the canyon
BRIDGE_X = (-6.5, 2.5)
BRIDGE_THICK = 0.3
RIM_WALL_HEIGHT = 1.3         # stone walls line the rims: no look into the canyon from above
PARAPET_HEIGHT = 1.2          # the deck's parapets: no look down from the bridge


def unstructured():
    """Seed 002's unstructured environment (section 6.2.3): few safe passes, large slopes, many
    obstacles and occlusions, a canyon the robot can drive along and a bridge across it that it
    can drive over and under, raised structures and a house; the start is the top-right corner."""
    n = 81
    half = 20.0
    rng = random.Random(2063)
    # Steep mounds (25..35 deg flanks: no pass for a 12 deg robot) that leave two passes between
    # the start and the canyon, and gentle waves elsewhere.
    mounds = [(10.0, 3.0, 2.2, 3.0), (13.0, -6.0, 2.0, 2.6), (5.0, 14.0, 1.8, 2.4),
              (-13.0, -9.0, 2.0, 3.0)]
    cx0, cx1 = CANYON_X

    def outside(v, lo_v, hi_v):
        return max(lo_v - v, 0.0, v - hi_v)

    heights = []
    for r in range(n):
        y = -half + 2 * half * r / (n - 1)
        row = []
        for c in range(n):
            x = -half + 2 * half * c / (n - 1)
            z = 0.15 * math.sin(0.35 * x + 0.2) * math.cos(0.3 * y - 0.4)
            for mx, my, amp, sigma in mounds:
                z += amp * math.exp(-((x - mx) ** 2 + (y - my) ** 2) / (2 * sigma ** 2))
            # Level ground (z = 0) where the bridge lands, fading out over 2 m.
            dx = max(BRIDGE_X[0] - 2.5 - x, 0.0, x - BRIDGE_X[1] - 2.5)
            dy = max(BRIDGE_Y[0] - 1.0 - y, 0.0, y - BRIDGE_Y[1] - 1.0)
            z *= smoothstep(math.hypot(dx, dy) / 2.0)
            # The canyon and its west branch: a level floor CANYON_DEPTH below z 0 (rising along
            # the ramp), walls rising from the floor's edge over CANYON_WALL_M, cut into
            # whatever ground is there.
            floor = -CANYON_DEPTH
            if y < CANYON_RAMP_Y[1]:
                t = (y - CANYON_RAMP_Y[0]) / (CANYON_RAMP_Y[1] - CANYON_RAMP_Y[0])
                floor = -CANYON_DEPTH * max(0.0, t)
            rise = CANYON_DEPTH / CANYON_WALL_M
            d_main = math.hypot(outside(x, cx0, cx1), max(0.0, y - CANYON_Y[1]))
            d_branch = math.hypot(outside(x, *BRANCH_X), outside(y, *BRANCH_Y))
            z = min(z, floor + rise * d_main, -CANYON_DEPTH + rise * d_branch)
            row.append(z)
        heights.append(row)
    # Flat within 2.5 m of the start.
    sx, sy = UNSTRUCTURED_START
    for r in range(n):
        y = -half + 2 * half * r / (n - 1)
        for c in range(n):
            x = -half + 2 * half * c / (n - 1)
            d = math.hypot(x - sx, y - sy)
            if d < 4.0:
                w = smoothstep((d - 2.5) / 1.5)
                heights[r][c] = (1 - w) * 0.0 + w * heights[r][c]
    lo = min(min(row) for row in heights)
    hi = max(max(row) for row in heights)
    with open(os.path.join(HERE, "unstructured_terrain.bin"), "wb") as out:
        out.write(struct.pack("<ii", n, n))
        for row in heights:
            out.write(struct.pack(f"<{n}f", *row))

    def ground(x, y):
        return terrain_at(heights, n, half, x, y, lo)

    def on_ground(name, x0, x1, y0, y1, height, rgba=WALL_RGBA):
        z0 = min(ground(x, y) for x in (x0, x1) for y in (y0, y1)) - 0.2
        return aabb(name, x0, x1, y0, y1, z0, z0 + 0.2 + height, rgba)

    g = ['    <geom name="terrain" type="hfield" hfield="terrain" pos="0 0 0" '
         'rgba="0.5 0.45 0.35 1"/>']
    # The bridge: a deck whose top is level with the ground where it lands, resting on both
    # rims, with parapets over the canyon.
    by0, by1 = BRIDGE_Y
    bx0, bx1 = BRIDGE_X
    deck_top = ground(bx0, (by0 + by1) / 2)  # the level ground where it lands
    g.append(aabb("bridge_deck", bx0, bx1, by0, by1, deck_top - BRIDGE_THICK, deck_top,
                  "0.5 0.42 0.32 1"))
    rw0, rw1 = cx0 - CANYON_WALL_M, cx1 + CANYON_WALL_M  # the rims' edges
    for i, (y0, y1) in enumerate(((by0, by0 + 0.2), (by1 - 0.2, by1))):
        g.append(aabb(f"parapet_{i}", rw0 - 0.5, rw1 + 0.5, y0, y1, deck_top,
                      deck_top + PARAPET_HEIGHT, "0.5 0.42 0.32 1"))
    floor_under = ground((cx0 + cx1) / 2, (by0 + by1) / 2)
    # Stone walls along the rims, open where the bridge lands: on the west from where the ramp
    # is 1 m deep, on the east from edge to edge (the ramp is entered from the west only, so the
    # bridge is the one pass between the halves); round the basin.
    wall_y0 = CANYON_RAMP_Y[0] + (CANYON_RAMP_Y[1] - CANYON_RAMP_Y[0]) / CANYON_DEPTH
    bw0, bw1 = BRANCH_X[0] - CANYON_WALL_M, BRANCH_Y[0] - CANYON_WALL_M
    top = BRANCH_Y[1] + CANYON_WALL_M
    rim_walls = [
        (rw0 - 0.3, rw0, wall_y0, by0),                    # west rim, south of the bridge
        (rw1, rw1 + 0.3, CANYON_Y[0], by0),                # east rim, south of the bridge
        (rw1, rw1 + 0.3, by1, half),                       # east rim, north of the bridge
        (bw0 - 0.3, rw0, bw1 - 0.3, bw1),                  # the basin's south rim
        (bw0 - 0.3, rw1 + 0.3, top, top + 0.3),            # the north rim
        (bw0 - 0.3, bw0, bw1 - 0.3, top + 0.3),            # the basin's west rim
    ]
    for i, (x0, x1, y0, y1) in enumerate(rim_walls):
        z0 = max(ground(x, y) for x in (x0, x1) for y in (y0, y1)) - 0.3
        g.append(aabb(f"rim_wall_{i}", x0, x1, y0, y1, z0, z0 + 0.3 + RIM_WALL_HEIGHT,
                      WALL_RGBA))
    # The world ends at a wall along the height field's edges: no path leaves it.
    edge = [-half + 0.5 * k for k in range(int(4 * half) + 1)]
    for name, (x0, x1, y0, y1), along in (
            ("edge_south", (-half, half, -half, -half + 0.3), [(x, -half) for x in edge]),
            ("edge_north", (-half, half, half - 0.3, half), [(x, half) for x in edge]),
            ("edge_west", (-half, -half + 0.3, -half, half), [(-half, y) for y in edge]),
            ("edge_east", (half - 0.3, half, -half, half), [(half, y) for y in edge])):
        z0 = max(ground(x, y) for x, y in along) - 0.3
        g.append(aabb(name, x0, x1, y0, y1, z0, z0 + 0.3 + RIM_WALL_HEIGHT, WALL_RGBA))
    # A house, a raised platform (1.2 m, too high to climb) and a low wall (occlusions).
    g.append(on_ground("house", -15.0, -9.0, 1.0, 6.0, 3.0))
    g.append(on_ground("platform", 4.0, 8.0, -14.0, -10.0, 1.2, FEATURE_RGBA))
    g.append(on_ground("wall", 4.0, 9.0, 8.0, 8.3, 1.5))
    # Rocks.
    rocks = []
    while len(rocks) < 12:
        x, y = rng.uniform(-17, 17), rng.uniform(-17, 17)
        if math.hypot(x - sx, y - sy) < 5 or rw0 - 1.5 <= x <= rw1 + 1.5:
            continue
        if bw0 - 1.5 <= x <= rw0 and bw1 - 1.5 <= y <= top + 1.5:
            continue
        if -16 <= x <= -8 and 0 <= y <= 7:
            continue
        rocks.append((x, y))
    for i, (x, y) in enumerate(rocks):
        s = rng.uniform(0.4, 1.0)
        g.append(f'    <geom name="rock_{i}" type="ellipsoid" size="{f(s)} {f(s * 0.8)} '
                 f'{f(s * 0.7)}" pos="{f(x)} {f(y)} {f(ground(x, y))}" '
                 f'euler="0 0 {rng.randint(0, 179)}" rgba="0.5 0.48 0.45 1"/>')
    wx0, wx1, wy0, wy1 = UNSTRUCTURED_WORK_AREA
    lines = header("unstructured", "unstructured: seed 002's unstructured environment, a 40 x "
                   "40 m height field with steep mounds, a canyon the robot drives along and a "
                   "bridge across it that it drives over and under, a house, a platform and rocks")
    lines += [
        "<!--",
        f"  Generated by generate_worlds.py. Terrain: unstructured_terrain.bin, {n} x {n}",
        f"  samples 0.5 m apart over x, y in -20..20, heights {f(lo)}..{f(hi)} m (shifted so the",
        "  lowest point is z = 0). Canyon: floor x -4..0, rims x -5 and 1, 2.2 m deep from y 0 to",
        "  its closed north end at y 14; from y 0 its floor rises to the rim level at y -17 (a",
        "  7.4 deg ramp, entered from the west); north of the bridge it opens west into a basin",
        "  (floor x -16..-4, y 10.5..16). Stone walls 1.3 m high line the rims (west: from y -9;",
        "  east: from y -20) and the basin, open where the bridge lands. Bridge: a 0.3 m deck",
        f"  x -6.5..2.5, y 6..9, its top {deck_top - floor_under:.2f} m above the canyon floor, with 1.2 m",
        "  parapets. Steep mounds (no pass for a 12 deg robot) at (10, 3), (13, -6), (5, 14),",
        "  (-13, -9). House x -15..-9, y 1..6, 3 m; platform",
        "  x 4..8, y -14..-10, 1.2 m; wall x 4..9, y 8..8.3, 1.5 m; 12 rocks (seed 2063).",
        f"  Start: ({f(sx)}, {f(sy)}), the top-right corner, flat within 2.5 m. A 1.3 m wall runs",
        f"  round the edge. Work area: x {f(wx0)}..{f(wx1)}, y {f(wy0)}..{f(wy1)}.",
        "-->",
    ]
    lines += heightfield_body("unstructured_terrain.bin", half, hi - lo, g)
    write("unstructured.xml", "\n".join(lines))


def terrain_at(heights, n, half, x, y, lo):
    """Terrain height (relative to the lowest point) at (x, y), bilinear."""
    cx = (x + half) / (2 * half) * (n - 1)
    cy = (y + half) / (2 * half) * (n - 1)
    c0, r0 = int(math.floor(cx)), int(math.floor(cy))
    c0, r0 = max(0, min(n - 2, c0)), max(0, min(n - 2, r0))
    tx, ty = cx - c0, cy - r0
    z = ((1 - tx) * (1 - ty) * heights[r0][c0] + tx * (1 - ty) * heights[r0][c0 + 1] +
         (1 - tx) * ty * heights[r0 + 1][c0] + tx * ty * heights[r0 + 1][c0 + 1])
    return z - lo


def heightfield_body(terrain_file, half, height, geoms):
    """The asset, sun and geoms of a world on a height field (terrain_file, +-half metres,
    height metres high, 0.5 m base), up to the end of the file."""
    return [
        "  <asset>",
        f'    <hfield name="terrain" file="{terrain_file}" size="{f(half)} {f(half)} '
        f'{f(height)} 0.5"/>',
        "  </asset>",
        "  <worldbody>",
        '    <light name="sun" directional="true" pos="0 0 40" dir="0.2 0.1 -1"/>',
    ] + geoms + ["  </worldbody>", "</mujoco>", ""]


# --------------------------------------------------------------------------------------------
# underwater (seed 004)

SEABED_RGBA = "0.55 0.5 0.38 1"
ROCK_RGBA = "0.35 0.33 0.3 1"
# Water: sea water's density and viscosity. MuJoCo's inertia-box model drags every moving body
# through it; option wind, set by a scenario's current, is the water's own velocity.
WATER_OPTION = ' density="1025" viscosity="0.0011"'


def underwater(name, summary, notes, geoms, centre=(20.0, 0.0), half=45.0):
    lines = header(name, summary, WATER_OPTION)
    lines += ["<!--", "  Generated by generate_worlds.py. " + notes[0]]
    lines += ["  " + n for n in notes[1:]]
    lines += [
        "-->",
        "  <worldbody>",
        f'    <light name="sun" directional="true" pos="{f(centre[0])} {f(centre[1])} 30" '
        'dir="0 0 -1"/>',
        f'    <geom name="seabed" type="plane" size="{f(half)} {f(half)} 0.1" '
        f'pos="{f(centre[0])} {f(centre[1])} 0" rgba="{SEABED_RGBA}"/>',
    ]
    lines += geoms + ["  </worldbody>", "</mujoco>", ""]
    write(f"{name}.xml", "\n".join(lines))


def cylinder(name, x, y, r, h, rgba=ROCK_RGBA):
    return (f'    <geom name="{name}" type="cylinder" size="{f(r)} {f(h / 2)}" '
            f'pos="{f(x)} {f(y)} {f(h / 2)}" rgba="{rgba}"/>')


def floor():
    underwater("floor", "floor: flat seabed and nothing else, under water (seed 004 test 17)",
               ["A seabed plane at z = 0, 90 x 90 m around (20, 0).",
                "Suggested start: (0, 0) at the AUV's 2.2 m, facing east."], [])


# Rocks between the start (0, 0) and the goal (35, 0): (name, x, y, shape, size, yaw_deg); every
# rock is 4 m high, above the AUV's 2.2 m, with vertical faces.
ROCKS = [("rock_1", 9.0, 1.0, "cylinder", (1.5,), 0.0),
         ("rock_2", 15.0, -2.6, "box", (1.5, 1.8), 30.0),
         ("rock_3", 21.0, 2.6, "cylinder", (2.0,), 0.0),
         ("rock_4", 27.0, -1.2, "box", (1.2, 1.6), -20.0)]
ROCK_H = 4.0


def rocks():
    g = []
    for name, x, y, shape, size, yaw in ROCKS:
        if shape == "cylinder":
            g.append(cylinder(name, x, y, size[0], ROCK_H))
        else:
            g.append(box(name, x, y, ROCK_H / 2, size[0], size[1], ROCK_H / 2, ROCK_RGBA,
                         euler=(0, 0, yaw)))
    underwater("rocks", "rocks: a seabed with four rocks between a start and a goal 35 m away "
               "(seed 004 test 13)",
               ["Rocks 4 m high with vertical faces: " + ", ".join(
                   f"{n} at ({f(x)}, {f(y)})" for n, x, y, *_ in ROCKS) + ".",
                "Start (0, 0) at the AUV's 2.2 m facing east; goal (35, 0)."], g)


# Four aligned columns, after the breakwater of Sant Feliu de Guixols: radius 1.5 m, 9 m apart
# on the line x = 18, 8 m high (above the water's working depth).
COLUMNS = [(18.0, y) for y in (-13.5, -4.5, 4.5, 13.5)]


def breakwater():
    g = [cylinder(f"column_{i + 1}", x, y, 1.5, 8.0) for i, (x, y) in enumerate(COLUMNS)]
    underwater("breakwater", "breakwater: four aligned cylindrical columns, after the breakwater "
               "of Sant Feliu de Guixols (seed 004 test 14)",
               ["Columns of radius 1.5 m, 8 m high, at x = 18 and y = -13.5, -4.5, 4.5, 13.5.",
                "Start (0, 0) at the AUV's 2.2 m facing east; goal (34, 0) through the middle "
                "gap."], g)


def cave():
    # A U-shaped enclosure open to the west: side walls y = +-7 (inner faces) from x = 6 to 22,
    # the back wall's inner face at x = 22; 8 m high, 0.5 m thick.
    t, h = 0.5, 8.0
    g = [aabb("cave_north", 6.0, 22.0 + t, 7.0, 7.0 + t, 0.0, h, ROCK_RGBA),
         aabb("cave_south", 6.0, 22.0 + t, -7.0 - t, -7.0, 0.0, h, ROCK_RGBA),
         aabb("cave_back", 22.0, 22.0 + t, -7.0, 7.0, 0.0, h, ROCK_RGBA)]
    underwater("cave", "cave: a U-shaped underwater enclosure open to the west (seed 004 test 15)",
               ["Inner faces: y = -7 and 7 from x = 6 to 22, x = 22 at the back; 8 m high.",
                "Suggested start: (0, 0) at the AUV's 2.2 m facing east, into the cave."], g)


def write(name, text):
    with open(os.path.join(HERE, name), "w") as out:
        out.write(text)


if __name__ == "__main__":
    tunnel()
    apartment()
    arena()
    room()
    hall()
    outdoor()
    terraces()
    simple()
    structured()
    unstructured()
    floor()
    rocks()
    breakwater()
    cave()
