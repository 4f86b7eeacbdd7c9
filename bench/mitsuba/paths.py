#!/usr/bin/env python3
"""Paths per second of Mitsuba 3's `llvm_ad_rgb` path tracer on a loupe scene,
the reference side of loupe's path-tracer benchmark (README.md beside this).

Reads what `bench-path-export` wrote (scene.json and one PLY per object),
builds the same scene with `mi.load_dict`, renders it once to JIT-compile the
kernels (timed and reported apart), then times `--runs` more renders.
Prints one JSON object; seconds is the runs' median and paths_per_second =
width * height * spp / seconds.

    python bench/mitsuba/paths.py EXPORT_DIR [--spp N] [--bounces N]
        [--size WxH] [--threads N] [--runs N] [--out image.exr]

Needs DRJIT_LIBLLVM_PATH naming an LLVM shared library (README.md).
"""

import argparse
import json
import math
import statistics
import time
from pathlib import Path

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

# loupe's `alpha` in shaders/lib/brdf.wgsl clamps roughness to this.
MIN_ROUGHNESS = 0.045
# Rows of the lat-long bitmap the environment's gradient is baked into; it
# is linear in d.y, and bilinear filtering over this many rows follows it
# to well under a percent.
ENV_ROWS = 64


def rgb(v):
    return {"type": "rgb", "value": [float(c) for c in v]}


def up_for(d):
    """The helper axis loupe's scene_gpu.rs uses: Y unless d is nearly vertical."""
    return [0, 0, 1] if abs(d[1]) > 0.99 else [0, 1, 0]


def look_at(origin, target, up):
    return mi.ScalarTransform4f().look_at(origin=origin, target=target, up=up)


def material(o):
    # loupe: Lambert diffuse weighted by (1 - F)(1 - metallic) plus GGX
    # (alpha = roughness^2, height-correlated Smith) with Schlick's Fresnel,
    # F0 = mix(0.04, base_color, metallic). `principled` has the same
    # parameters and alpha; its default specular 0.5 gives F0 = 0.04. It is
    # not the same BRDF (README.md, "Differences"). Two-sided because loupe
    # shades both faces (gbuffer.wgsl turns the normal to the viewer).
    return {
        "type": "twosided",
        "bsdf": {
            "type": "principled",
            "base_color": rgb(o["base_color"]),
            "metallic": float(o["metallic"]),
            "roughness": max(float(o["roughness"]), MIN_ROUGHNESS),
        },
    }


def rect(light, flip):
    """A rect light as a `rectangle` (local [-1, 1]^2, normal +z) with an
    `area` emitter, which emits on the normal's side only; a two-sided one is
    two of these back to back. The shape must not reflect: black BSDF."""
    n, r, u, p = light["normal"], light["right"], light["up"], light["position"]
    hx, hy = light["half_size"]
    # The back face sits a hair behind the front so neither hides the other.
    off = -1e-4 if flip else 0.0
    m = [[r[i] * hx, u[i] * hy, n[i], p[i] + off * n[i]] for i in range(3)] + [[0, 0, 0, 1]]
    return {
        "type": "rectangle",
        "to_world": mi.ScalarTransform4f(m),
        "flip_normals": flip,
        "emitter": {"type": "area", "radiance": rgb(light["radiance"])},
        "bsdf": {"type": "diffuse", "reflectance": rgb([0, 0, 0])},
    }


def lights(scene):
    out = {}
    for i, l in enumerate(scene["lights"]):
        kind = l["type"]
        if kind == "directional":
            out[f"light{i}"] = {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
        elif kind == "point":
            out[f"light{i}"] = {"type": "point", "position": l["position"], "intensity": rgb(l["radiant_intensity"])}
        elif kind == "spot":
            # Mitsuba ramps linearly in angle from beam_width to cutoff_angle;
            # loupe uses smoothstep in cosine between inner and outer.
            p, d = l["position"], l["direction"]
            out[f"light{i}"] = {
                "type": "spot",
                "to_world": look_at(p, [p[k] + d[k] for k in range(3)], up_for(d)),
                "intensity": rgb(l["radiant_intensity"]),
                "cutoff_angle": float(l["outer_deg"]),
                "beam_width": float(l["inner_deg"]),
            }
        elif kind == "rect":
            out[f"light{i}"] = rect(l, flip=False)
            if l["two_sided"]:
                out[f"light{i}back"] = rect(l, flip=True)
        else:
            raise ValueError(f"unknown light type {kind!r}")
    return out


def environment(env):
    """None (black), a constant, or the gradient as a lat-long envmap."""
    top = [c * env["intensity"] for c in env["top"]]
    bottom = [c * env["intensity"] for c in env["bottom"]]
    if top == bottom:
        return None if max(top) <= 0 else {"type": "constant", "radiance": rgb(top)}
    # Mitsuba's envmap maps row v to d.y = cos(pi * v) (row 0 straight up);
    # every column of a row has the same radiance.
    cols = 4
    values = []
    for row in range(ENV_ROWS):
        t = math.cos(math.pi * (row + 0.5) / ENV_ROWS) * 0.5 + 0.5
        values += [b + (a - b) * t for a, b in zip(top, bottom)] * cols
    bitmap = mi.Bitmap(mi.TensorXf(mi.Float(values), shape=(ENV_ROWS, cols, 3)))
    return {"type": "envmap", "bitmap": bitmap}


def scene_dict(export, scene, size, spp, bounces):
    cam = scene["camera"]
    width, height = size
    d = {
        "type": "scene",
        # loupe's path_bounces counts indirect bounces (0 = direct light
        # only); Mitsuba's max_depth counts path segments, 1 = emitters seen
        # by the camera, 2 = direct light: max_depth = bounces + 2. Russian
        # roulette off (rr_depth = max_depth) so every path runs to its full
        # depth unless it escapes.
        "integrator": {"type": "path", "max_depth": bounces + 2, "rr_depth": bounces + 2},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam["fov_deg"]),
            "near_clip": float(cam["near"]),
            "far_clip": float(cam["far"]),
            "to_world": look_at(cam["position"], cam["target"], cam["up"]),
            # One independent sample per path, box-filtered into its pixel.
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb", "rfilter": {"type": "box"}},
        },
    }
    for i, o in enumerate(scene["objects"]):
        # Flat shading: the export has no normals (loupe's raster
        # interpolates vertex normals).
        d[f"object{i}"] = {"type": "ply", "filename": str(export / o["ply"]), "face_normals": True, "bsdf": material(o)}
    d.update(lights(scene))
    env = environment(scene["environment"])
    if env is not None:
        d["environment"] = env
    return d


def render(scene, spp, seed):
    start = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    # Kernels run asynchronously on Dr.Jit's thread pool: wait for them.
    dr.sync_thread()
    return image, time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export", type=Path, help="directory bench-path-export wrote")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--bounces", type=int, default=3, help="indirect bounces, as loupe's path_bounces")
    ap.add_argument("--size", default="640x360", help="WxH")
    ap.add_argument("--threads", type=int, default=0, help="Dr.Jit's thread pool size (0: every core)")
    ap.add_argument("--runs", type=int, default=3, help="timed renders; their median is reported")
    ap.add_argument("--out", type=Path, help="write the first timed render here (.exr)")
    args = ap.parse_args()

    if args.threads:
        dr.set_thread_count(args.threads)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    scene = json.loads((args.export / "scene.json").read_text())
    mi_scene = mi.load_dict(scene_dict(args.export, scene, size, args.spp, args.bounces))

    # The first render compiles the kernels (LLVM), or loads them from
    # Dr.Jit's disk cache (~/.drjit); the history says how long that took.
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    _, warmup = render(mi_scene, args.spp, seed=0)
    jit = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    # Other seeds reuse the compiled kernels (the seed is not baked in).
    runs = [render(mi_scene, args.spp, seed=1 + i) for i in range(args.runs)]
    image, seconds = runs[0][0], statistics.median(t for _, t in runs)
    if args.out:
        mi.util.write_bitmap(str(args.out), image)

    width, height = size
    print(json.dumps({
        "scene": scene["scene"],
        "renderer": f"mitsuba {mi.__version__} llvm_ad_rgb",
        "size": [width, height],
        "spp": args.spp,
        "bounces": args.bounces,
        "max_depth": args.bounces + 2,
        "threads": dr.thread_count(),
        "triangles": sum(o["triangles"] for o in scene["objects"]),
        "media_skipped": scene["media"],
        "seconds": round(seconds, 4),
        "runs": [round(t, 4) for _, t in runs],
        "paths_per_second": round(width * height * args.spp / seconds),
        "warmup_seconds": round(warmup, 4),
        "jit_seconds": round(sum(k["codegen_time"] + k["backend_time"] for k in jit) / 1e3, 4),
        "jit_from_cache": all(k["cache_hit"] for k in jit),
    }))


if __name__ == "__main__":
    main()
