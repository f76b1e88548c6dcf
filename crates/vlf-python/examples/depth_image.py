"""Bakes a mesh (or opens a baked field), renders a depth image with one closest-hit query per
pixel, counts the surfaces along every pixel's ray, and tells inside from outside for a few
points. Writes the depth image as a PGM file.

    python examples/depth_image.py fixtures/meshes/bunny.obj depth.pgm
"""

import sys
import time

import numpy as np

import vlf


def camera_rays(center, radius, width, height):
    """Rays of a pinhole camera looking at the scene from +z, one per pixel."""
    eye = center + np.array([0.0, 0.0, 2.5 * radius])
    ys, xs = np.mgrid[0:height, 0:width]
    x = (xs + 0.5) / width * 2 - 1
    y = 1 - (ys + 0.5) / height * 2
    directions = np.stack([x * 0.5, y * 0.5 * height / width, -np.ones_like(x)], axis=-1).reshape(-1, 3)
    return eye, directions


def main(mesh_path, out_path, width=320, height=240):
    start = time.perf_counter()
    field = vlf.bake(mesh_path, out_path + ".vlf", cache_dir=vlf.default_cache_dir())
    print(f"{field!r}: {field.bake_info['cache']} in {time.perf_counter() - start:.2f} s")
    center, radius = field.bounding_sphere
    eye, directions = camera_rays(center, radius, width, height)

    hits = field.closest_hits(eye, directions)  # one origin for every pixel
    depth = np.where(hits.hit, hits.t, np.nan).reshape(height, width)
    shade = np.zeros_like(depth)
    seen = ~np.isnan(depth)
    lo, hi = np.nanmin(depth), np.nanmax(depth)
    shade[seen] = 255 - 200 * (depth[seen] - lo) / max(hi - lo, 1e-9)
    with open(out_path, "wb") as f:
        f.write(b"P5 %d %d 255\n" % (width, height))
        f.write(shade.astype(np.uint8).tobytes())

    layers = field.hit_counts(eye, directions).reshape(height, width)
    middle_row = directions[(height // 2) * width : (height // 2 + 1) * width]
    every = field.all_hits(eye, middle_row, max_hits=8)
    print(f"{seen.sum()} of {width * height} pixels see the mesh; up to {layers.max()} surfaces behind a pixel")
    deepest = int(np.argmax(every.counts))
    print(f"the middle row's pixel {deepest} meets surfaces at t = {every.ray(deepest).t}")

    points = center + (np.random.default_rng(0).random((5, 3)) - 0.5) * radius
    inside = field.hit_counts(points, [0.43, 0.61, 0.65]) % 2 == 1
    print("inside (by the parity of crossings):", inside.tolist())


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "fixtures/meshes/bunny.obj", sys.argv[2] if len(sys.argv) > 2 else "depth.pgm")
