#!/usr/bin/env python3
"""shoot.py -- libbspray from Python, through ctypes and the shared library.

The same program as shoot.c: load a scene, build the default structure (the
SAH kd-tree), answer a closest-hit query from the eye through the centre of
the view, a shadow query from that hit to the first light, and a batch of a
G x G grid of eye rays on every core. It prints what shoot.c prints, to the
bit: the rays are made by the same operations in the same order.

    python3 shoot.py [LIBRARY [SCENE [G]]]

LIBRARY: the shared library (default: build/libbspray.so, beside the
examples/ folder; installed: libbspray.so.0.2). SCENE: default spd:balls.
G: default 256.
"""
import ctypes
import math
import os
import sys
from ctypes import POINTER, byref, c_char, c_char_p, c_double, c_int, c_size_t, c_uint32
from ctypes import c_uint64, c_void_p


class Vec3(ctypes.Structure):
    _fields_ = [("x", c_double), ("y", c_double), ("z", c_double)]


class Ray(ctypes.Structure):
    _fields_ = [("org", Vec3), ("dir", Vec3), ("tmin", c_double), ("tmax", c_double)]


class Hit(ctypes.Structure):
    _fields_ = [("t", c_double), ("prim", c_uint32), ("u", c_double), ("v", c_double)]


class Error(ctypes.Structure):
    _fields_ = [("status", c_int), ("message", c_char * 1024)]


class Camera(ctypes.Structure):
    _fields_ = [("frm", Vec3), ("at", Vec3), ("up", Vec3), ("angle_deg", c_double),
                ("hither", c_double), ("res_x", c_int), ("res_y", c_int)]


class Light(ctypes.Structure):
    _fields_ = [("pos", Vec3), ("color", c_double * 3), ("has_color", c_int)]


class Counters(ctypes.Structure):
    _fields_ = [(name, c_uint64) for name in
                ("rays", "isect_tests", "traversal_steps", "leaves_visited", "empty_leaves",
                 "mailbox_hits")]


NO_PRIM = 0xFFFFFFFF


def load(path):
    lib = ctypes.CDLL(path)
    sig = {
        "bsp_scene_load": (c_int, [c_char_p, POINTER(c_void_p), POINTER(Error)]),
        "bsp_scene_destroy": (None, [c_void_p]),
        "bsp_scene_camera": (POINTER(Camera), [c_void_p]),
        "bsp_scene_light_count": (c_size_t, [c_void_p]),
        "bsp_scene_light": (POINTER(Light), [c_void_p, c_size_t]),
        "bsp_accel_build": (c_int, [c_void_p, c_void_p, POINTER(c_void_p), POINTER(Error)]),
        "bsp_accel_destroy": (None, [c_void_p]),
        "bsp_query_create": (c_void_p, [c_void_p]),
        "bsp_query_destroy": (None, [c_void_p]),
        "bsp_intersect": (c_int, [c_void_p, c_void_p, POINTER(Ray), POINTER(Hit)]),
        "bsp_occluded_from": (c_int, [c_void_p, c_void_p, POINTER(Ray), c_uint32]),
        "bsp_intersect_batch": (c_int, [c_void_p, POINTER(Ray), c_void_p, c_size_t, c_int,
                                        POINTER(Hit), POINTER(Counters), POINTER(Error)]),
    }
    for name, (res, args) in sig.items():
        f = getattr(lib, name)
        f.restype, f.argtypes = res, args
    return lib


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    lib_path = argv[1] if len(argv) > 1 else os.path.join(here, "..", "build", "libbspray.so")
    path = argv[2] if len(argv) > 2 else "spd:balls"
    G = int(argv[3]) if len(argv) > 3 else 256
    if not 1 <= G <= 4096:
        print("shoot.py: the grid size G must be from 1 to 4096", file=sys.stderr)
        return 2
    lib = load(lib_path)
    err = Error()
    scene = c_void_p()
    if lib.bsp_scene_load(path.encode(), byref(scene), byref(err)) != 0:
        print("shoot.py: " + err.message.decode(), file=sys.stderr)
        return 1
    accel = c_void_p()
    if lib.bsp_accel_build(scene, None, byref(accel), byref(err)) != 0:  # None: the defaults
        print("shoot.py: " + err.message.decode(), file=sys.stderr)
        lib.bsp_scene_destroy(scene)
        return 1
    cam_p = lib.bsp_scene_camera(scene)
    cam = cam_p.contents if cam_p else None
    eye = cam.frm if cam else Vec3(0, 0, 10)
    at = cam.at if cam else Vec3(0, 0, 0)
    d = Vec3(at.x - eye.x, at.y - eye.y, at.z - eye.z)

    q = lib.bsp_query_create(accel)  # one query per thread: its mailbox and counters
    ray = Ray(eye, d, 0.0, math.inf)
    hit = Hit()
    if lib.bsp_intersect(accel, q, byref(ray), byref(hit)):
        print("centre ray: primitive %u at t = %s" % (hit.prim, c17(hit.t)))
        if lib.bsp_scene_light_count(scene) > 0:
            p = Vec3(eye.x + hit.t * d.x, eye.y + hit.t * d.y, eye.z + hit.t * d.z)
            lpos = lib.bsp_scene_light(scene, 0).contents.pos
            shadow = Ray(p, Vec3(lpos.x - p.x, lpos.y - p.y, lpos.z - p.z), 0.0, 1.0)
            blocked = lib.bsp_occluded_from(accel, q, byref(shadow), hit.prim)
            print("light 0 is %s" % ("blocked" if blocked else "visible"))
    else:
        print("centre ray: miss")
    lib.bsp_query_destroy(q)

    # a batch: the G x G grid of shoot.c, by the same arithmetic
    up = cam.up if cam else Vec3(0, 1, 0)
    r = Vec3(d.y * up.z - d.z * up.y, d.z * up.x - d.x * up.z, d.x * up.y - d.y * up.x)
    u = Vec3(r.y * d.z - r.z * d.y, r.z * d.x - r.x * d.z, r.x * d.y - r.y * d.x)
    length = math.sqrt(d.x * d.x + d.y * d.y + d.z * d.z)
    rl = math.sqrt(r.x * r.x + r.y * r.y + r.z * r.z)
    ul = math.sqrt(u.x * u.x + u.y * u.y + u.z * u.z)
    if not (rl > 0.0 and ul > 0.0):
        print("shoot.py: the view direction is parallel to up", file=sys.stderr)
        return 1
    rays = (Ray * (G * G))()
    for j in range(G):
        for i in range(G):
            a = ((i + 0.5) / G - 0.5) * length / rl
            b = ((j + 0.5) / G - 0.5) * length / ul
            rays[j * G + i] = Ray(eye, Vec3(d.x + a * r.x + b * u.x, d.y + a * r.y + b * u.y,
                                            d.z + a * r.z + b * u.z), 0.0, math.inf)
    hits = (Hit * (G * G))()
    c = Counters()
    if lib.bsp_intersect_batch(accel, rays, None, G * G, 0, hits, byref(c), byref(err)) != 0:
        print("shoot.py: " + err.message.decode(), file=sys.stderr)
        return 1
    n_hit = sum(1 for h in hits if h.prim != NO_PRIM)
    print("grid: %d of %d rays hit; %.2f tests and %.2f traversal steps per ray"
          % (n_hit, G * G, c.isect_tests / c.rays, c.traversal_steps / c.rays))
    lib.bsp_accel_destroy(accel)
    lib.bsp_scene_destroy(scene)
    return 0


def c17(x):
    """x as C's printf("%.17g") writes it."""
    return "%.17g" % x


if __name__ == "__main__":
    sys.exit(main(sys.argv))
