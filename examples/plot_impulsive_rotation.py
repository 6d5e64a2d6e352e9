"""
The impulsive rotation (the paper's Figs. 11 and 12)
====================================================

The paper's second vacuum experiment: the clamp holding a 100 mm strip is rotated
abruptly, θ = 3.2·10⁴ t⁴ up to 0.2 rad at 0.05 s, then at a constant 16 rad/s to
1.32 rad (75.6°) at 0.12 s, where it stops. It turns about a rotation centre 2.8 mm above
the clamp edge (the offset the paper fitted). The strip, much more flexible than the
motion is fast, is left behind, then whips round and swings about its new root.

What to read off: the clamp angle θ(t) the scene imposes (Fig. 12, which the paper
fitted to its encoder), how far the strip lags behind it, and when the free end moves
fastest. The θ(t) coefficients are illustrative (Fig. 12 is not in the paper's text);
``warpcloth clamp fit-angle`` fits them to an encoder record (:doc:`/calibration`).
"""

# %%
# Run the bundled scene
# ---------------------
# No ``out=``: the result stays in memory (:class:`warpcloth.RunResult`), probes as
# ``[sample]`` series and frames as ``[frame, variant, node, xy]`` (m, from the clamp
# edge). ``WARPCLOTH_EXAMPLES_QUICK=1`` records 0.25 s instead of 0.5 s.
import os

import matplotlib.pyplot as plt
import numpy as np

import warpcloth as wc

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
overrides = {"run.duration_s": 0.25} if QUICK else {}

result = wc.run("impulsive_rotation", overrides)
scene = result.scenes[0]
for segment in scene.clamp.segments:
    print(
        f"θ(t) on [{segment.t_start_s:g}, {segment.t_end_s:g}] s: coefficients {segment.theta_coefficients_si} rad/s^k"
    )
print(
    f"h = {scene.strip.spacing_mm:g} mm ({scene.n_nodes} nodes, {scene.n_clamped} in the clamp), "
    f"dt = {scene.integrator.dt_s:g} s: {result.strip_steps:.3g} strip-steps in {result.wall_time_s:.2f} s"
)

# %%
# How far the strip lags behind the clamp
# ---------------------------------------
# The clamp's direction is θ from the vertical; the strip's is the angle φ of its chord,
# from the clamp edge to the free end. While the clamp turns the strip stays nearly
# vertical (φ peaks at about 17° against the clamp's 75.6° in the full run): the motion is
# far faster than the strip's own swing (period ≈ 0.5 s), so gravity and inertia, not
# bending, set its shape.
t = result.t
theta = result.probe("clamp_angle", 0)
nc = scene.n_clamped
edge, tip = result.frames[:, 0, nc - 1], result.frames[:, 0, -1]
phi = np.arctan2(tip[:, 0] - edge[:, 0], edge[:, 1] - tip[:, 1])
speed = result.probe("tip_speed", 0)
fastest = int(np.argmax(speed))
print(f"clamp angle at the end: {np.degrees(theta[-1]):.2f}°")
print(f"strip chord angle: at most {np.degrees(phi.max()):.1f}° at t = {result.frame_times[phi.argmax()]:.3f} s")
print(f"largest lag θ − φ: {np.degrees(np.max(np.interp(result.frame_times, t, theta) - phi)):.1f}°")
print(f"free end fastest at t = {t[fastest]:.4f} s: {speed[fastest]:.3f} m/s")

# %%
# The shapes (Fig. 11)
# --------------------
# Every 1/60 s (the paper's video rate): left while the clamp turns, right after it has
# stopped. The clamp is drawn grey, its rotation centre as a cross; positions are from
# the clamp edge at rest.
t_stop = scene.clamp.segments[-1].t_end_s
centre = (scene.clamp.rotation_centre_dx_mm, scene.clamp.rotation_centre_dy_mm)
fig, axes = plt.subplots(1, 2, figsize=(8.5, 5.4), sharey=True)
for ax, chosen, title in (
    (axes[0], result.frame_times <= t_stop + 1e-9, "while the clamp turns"),
    (axes[1], result.frame_times > t_stop, "after the clamp stops"),
):
    frames = np.flatnonzero(chosen)
    colour = plt.Normalize(result.frame_times[frames].min(), result.frame_times[frames].max())
    for f in frames:
        xy = result.frames[f, 0] * 1e3
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=plt.cm.viridis(colour(result.frame_times[f])), lw=1.2)
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.3", lw=4, solid_capstyle="butt")
    ax.plot(*centre, "k+", ms=10)
    ax.set(title=title, xlabel="x from the clamp edge (mm)", aspect="equal")
    fig.colorbar(plt.cm.ScalarMappable(colour, "viridis"), ax=ax, label="t (s)", shrink=0.8)
axes[0].set_ylabel("y from the clamp edge (mm)")
fig.tight_layout()

# %%
# The clamp angle (Fig. 12)
# -------------------------
# Top: θ(t) as recorded by the ``clamp_angle`` probe (the scene's piecewise polynomial:
# the quartic start, the straight 16 rad/s line, the stop) and the strip's chord angle φ.
# Bottom: the free end's speed; it peaks after the clamp has stopped, when the strip
# whips round.
fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, height_ratios=[3, 2])
top.plot(t, np.degrees(theta), lw=1.4, label="clamp θ")
top.plot(result.frame_times, np.degrees(phi), "o-", ms=3, lw=1, label="strip chord φ")
for segment in scene.clamp.segments:
    top.axvline(segment.t_end_s, color="0.7", lw=0.6, ls="--")
top.set(ylabel="angle from the vertical (deg)", title="clamp rotation and the strip's response")
top.legend(fontsize=8)
bottom.plot(t, speed, lw=1.2, color="C2")
bottom.plot(t[fastest], speed[fastest], "k.", ms=8)
bottom.set(xlabel="t (s)", ylabel="free-end speed (m/s)")
fig.tight_layout()
plt.show()
