#!/usr/bin/env python3
"""Camera fit from GCPs: cliffmap against peers on the same data and free parameters
(docs/registration.md).

Data: Engabreen IMG_8902, the 28 GCPs of gcp8902.txt (ImGRAFT text, "+" tokens summed,
1-based pixels) and ImGRAFT's camera (position fixed by the survey).
- A: yaw, pitch, roll, fx, fy, k1 free, position fixed: scipy.optimize.least_squares
  (method "lm", the ImGRAFT camera model written out below) against cliffmap.
- B: yaw, pitch, roll, x, y, z free, intrinsics fixed to ImGRAFT's: OpenCV
  solvePnPRansac + solvePnPRefineLM and pycolmap estimate_and_refine_absolute_pose
  (OPENCV camera model with k1 only) against cliffmap.
Each from ImGRAFT's camera and from a perturbed start (angles +2 / -1 / +1 deg, focal -3 %,
k1 0 in A; position +5, -5, +3 m in B; OpenCV and pycolmap need no start). Times: median of
RUNS in-process calls (cliffmap: examples/fit_camera_bench.rs, run by this script in the
same session).

    python3 benches/peers/fit_camera_peers.py [RUNS]

Installs numpy, scipy, opencv-python-headless and pycolmap with pip if missing.
"""
import json
import math
import os
import subprocess
import sys
import time

def ensure(mod, pkg):
    try:
        __import__(mod)
    except ImportError:
        subprocess.check_call([sys.executable, "-m", "pip", "install", "--quiet", pkg])

for m, p in [("numpy", "numpy"), ("scipy", "scipy"), ("cv2", "opencv-python-headless"), ("pycolmap", "pycolmap")]:
    ensure(m, p)

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import pycolmap  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "..", "shared", "data", "real", "engabreen")
RUNS = int(sys.argv[1]) if len(sys.argv) > 1 else 50


def number(tok):
    tok = tok.replace("-", "+-").replace("e+-", "e-").replace("E+-", "E-")
    return sum(float(t) for t in tok.split("+") if t)


def read_gcps():
    pts = []
    for line in open(os.path.join(DATA, "gcp8902.txt")):
        line = line.split("%")[0].strip()
        if not line:
            continue
        v = [number(t) for t in line.replace(",", " ").split()[:5]]
        pts.append(v)
    a = np.array(pts)
    return a[:, :3], a[:, 3:5] - 1.0  # 0-based pixel centres


def rotation(yaw, pitch, roll):
    sy, cy = math.sin(yaw), math.cos(yaw)
    sp, cp = math.sin(pitch), math.cos(pitch)
    sr, cr = math.sin(roll), math.cos(roll)
    f = np.array([cp * cy, cp * sy, -sp])
    r0 = np.array([sy, -cy, 0.0])
    d0 = np.cross(f, r0)
    right = cr * r0 + sr * d0
    down = -sr * r0 + cr * d0
    return np.array([right, down, f])


def project(R, pos, fx, fy, cx, cy, k1, X):
    c = (X - pos) @ R.T
    x, y = c[:, 0] / c[:, 2], c[:, 1] / c[:, 2]
    r2 = np.minimum(x * x + y * y, 4.0)
    d = 1 + k1 * r2
    return np.stack([fx * x * d + cx, fy * y * d + cy], axis=1)


def rmse(pred, uv):
    return float(np.sqrt(np.mean(np.sum((pred - uv) ** 2, axis=1))))


def timed(fn):
    ts = []
    out = None
    for _ in range(RUNS):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return out, float(np.median(ts))


def angles_of(R):
    f = R[2]
    pitch = math.asin(max(-1.0, min(1.0, -f[2])))
    yaw = math.atan2(f[1], f[0])
    r0 = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    d0 = np.cross(f, r0)
    roll = math.atan2(R[0] @ d0 - R[1] @ r0, R[0] @ r0 + R[1] @ d0)
    return math.degrees(yaw) % 360.0, math.degrees(pitch), math.degrees(roll)


def main():
    X, uv = read_gcps()
    cam = json.load(open(os.path.join(DATA, "engabreen_camera_IMG_8902.json")))
    pos = np.array(cam["camera_xyz_utm33n_nn1954_m"], dtype=float)
    yaw, pitch, roll = cam["viewdir_yaw_pitch_roll_rad"]
    fx, fy = cam["f_px"]
    cx, cy = cam["c_px_0based"]
    k1 = cam["k1"]
    rows = []
    d2r = math.pi / 180
    # --- A: scipy least_squares, position fixed
    def resid_a(p):
        R = rotation(p[0], p[1], p[2])
        return (project(R, pos, p[3], p[4], cx, cy, p[5], X) - uv).ravel()
    starts_a = {
        "imgraft": [yaw, pitch, roll, fx, fy, k1],
        "perturbed": [yaw + 2 * d2r, pitch - 1 * d2r, roll + 1 * d2r, 0.97 * fx, 0.97 * fy, 0.0],
    }
    for name, x0 in starts_a.items():
        sol, t = timed(lambda: least_squares(resid_a, x0, method="lm", x_scale="jac"))
        p = sol.x
        y, pi, ro = angles_of(rotation(p[0], p[1], p[2]))
        rows.append({"config": "A", "method": "scipy least_squares (lm)", "start": name,
                     "rmse_px": rmse(project(rotation(*p[:3]), pos, p[3], p[4], cx, cy, p[5], X), uv),
                     "yaw_deg": y, "pitch_deg": pi, "roll_deg": ro, "fx": p[3], "fy": p[4], "k1": p[5], "seconds_median": t})
    # --- B: OpenCV and pycolmap, intrinsics fixed
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    dist = np.array([k1, 0.0, 0.0, 0.0])
    Xl = X - pos  # a local origin at the surveyed position (the solvers work in doubles anyway)

    def opencv():
        ok, rvec, tvec, inl = cv2.solvePnPRansac(Xl, uv, K, dist, flags=cv2.SOLVEPNP_EPNP, reprojectionError=8.0,
                                                 iterationsCount=1000, confidence=0.999)
        rvec, tvec = cv2.solvePnPRefineLM(Xl, uv, K, dist, rvec, tvec)
        return rvec, tvec
    (rvec, tvec), t = timed(opencv)
    R, _ = cv2.Rodrigues(rvec)
    C = -R.T @ tvec.ravel() + pos
    y, pi, ro = angles_of(R)
    rows.append({"config": "B", "method": "OpenCV solvePnPRansac (EPnP) + solvePnPRefineLM", "start": "none",
                 "rmse_px": rmse(project(R, C, fx, fy, cx, cy, k1, X), uv), "yaw_deg": y, "pitch_deg": pi, "roll_deg": ro,
                 "position": C.tolist(), "seconds_median": t})
    camera = pycolmap.Camera(model="OPENCV", width=cam["image_size_wh"][0], height=cam["image_size_wh"][1],
                             params=[fx, fy, cx + 0.5, cy + 0.5, k1, 0.0, 0.0, 0.0])

    def colmap():
        est = pycolmap.AbsolutePoseEstimationOptions()
        est.ransac.max_error = 8.0
        return pycolmap.estimate_and_refine_absolute_pose(uv + 0.5, Xl, camera, est)
    res, t = timed(colmap)
    if res is not None:
        cw = res["cam_from_world"]
        M = np.array(cw.matrix())
        R, tv = M[:, :3], M[:, 3]
        C = -R.T @ tv + pos
        y, pi, ro = angles_of(R)
        rows.append({"config": "B", "method": "pycolmap estimate_and_refine_absolute_pose", "start": "none",
                     "rmse_px": rmse(project(R, C, fx, fy, cx, cy, k1, X), uv), "yaw_deg": y, "pitch_deg": pi,
                     "roll_deg": ro, "position": C.tolist(), "seconds_median": t,
                     "inliers": int(np.sum(res["inlier_mask"]))})
    # --- cliffmap, same session
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--example", "fit_camera_bench", "--", str(RUNS)],
                         cwd=ROOT, check=True, capture_output=True, text=True).stdout
    rows += [json.loads(l) for l in out.splitlines() if l.startswith("{")]
    print(f"Engabreen IMG_8902, 28 GCPs, median of {RUNS} in-process calls\n")
    print("| config | method | start | RMSE px | yaw ° | pitch ° | roll ° | position (m from the survey) | ms |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        p = r.get("position")
        d = "fixed" if p is None or r["config"] == "A" else ", ".join(f"{a - b:+.2f}" for a, b in zip(p, pos))
        print(f"| {r['config']} | {r['method']} | {r['start']} | {r['rmse_px']:.3f} | {r['yaw_deg']:.4f} | "
              f"{r['pitch_deg']:.4f} | {r['roll_deg']:.4f} | {d} | {1e3 * r['seconds_median']:.3f} |")


if __name__ == "__main__":
    main()
