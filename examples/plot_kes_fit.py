"""
A material from KES-FB data
===========================

A fabric enters warpcloth through the Kawabata instruments: a KES-FB1 tensile loop gives
the quartic tensile law T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴, and a KES-FB2 bending loop
the hysteretic bending law's rigidity D, hysteresis amplitude D1, steepness α and
loop-closing curvature K0 (:doc:`/model` §13). This is ``warpcloth material fit-kes``
step by step, on the bundled example loops.

The bundled loops are synthetic: made from the default wool/nylon material (D = 0.10
gf·cm²/cm, D1 = 0.04 gf·cm/cm, α = 5 cm, K0 = 2.5 1/cm) with σ = 2 gf/cm and
0.002 gf·cm/cm of Gaussian noise (``scenes/data/make_kes_examples.py``), so what to read
off is how close the fit comes to the truth, and whether its residual is the noise.
"""

# %%
# Read the loops and fit them
# ---------------------------
# The readers take a path or a bundled example's name; they infer the strain unit from
# the header (``strain_percent`` here) and validate the loops (a loading branch that goes
# back, a bending loop that does not close, ... are errors naming the file and line).
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import warpcloth as wc
from warpcloth.calibrate import kes
from warpcloth.metrics import swing_summary
from warpcloth.scene import read_material_file

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
workdir = Path(tempfile.mkdtemp(prefix="warpcloth-kes-"))

tensile = kes.read_tensile_csv("kes_fb1_example")
bending = kes.read_bending_csv("kes_fb2_example")
print(f"tensile: {len(tensile.strain)} points, first column read as {tensile.strain_unit}")
print(f"bending: {len(bending.curvature)} points, largest |K| = {bending.k0:g} 1/cm")
fit = kes.fit_kes(tensile, bending)

# %%
# The fitted laws and their verdict
# ---------------------------------
# Each curve's RMS is judged against the noise of its own samples (4th differences): an
# RMS near the noise means the law describes the loop and only the noise is left;
# ``poor_fit`` would mean above 3× the noise. The full example recovers D = 0.1001,
# D1 = 0.0398 and α = 5.05 against the truth 0.10, 0.04 and 5, at an RMS of
# 0.00213 gf·cm/cm (the noise added: 0.002).
truth = read_material_file("wool90-nylon10")["material"]
status, problems = fit.verdict()
print(f"status: {status} {problems or ''}")
b = fit.bending
print(
    f"tensile a1..a4 = {', '.join(f'{a:.5g}' for a in fit.tensile.coefficients)} gf/cm, "
    f"RMS {fit.tensile.rms_gf_per_cm:.3g} gf/cm"
)
for name, value, key in (
    ("D", b.rigidity_gf_cm2_per_cm, "bending_rigidity_gf_cm2_per_cm"),
    ("D1", b.d1_gf_cm_per_cm, "hysteresis_d1_gf_cm_per_cm"),
    ("alpha", b.alpha_cm, "hysteresis_alpha_cm"),
    ("K0", b.k0_per_cm, "hysteresis_k0_per_cm"),
):
    print(f"{name:>5} = {value:.5g}   (truth {truth[key]:g})")
print(f"bending RMS {b.rms_gf_cm_per_cm:.4g} gf·cm/cm ({b.rms_relative:.2%} of the moment range)")
tk, bk = fit.tensile_kes, fit.bending_kes
print(
    f"KES values: EMT {tk.emt_percent:.3g} %, WT {tk.wt_gf_cm_per_cm2:.3g} gf·cm/cm², LT {tk.lt:.3g}, "
    f"RT {tk.rt_percent:.3g} %, B {bk.b_gf_cm2_per_cm:.4g} gf·cm²/cm, 2HB {bk.hb2_gf_cm_per_cm:.4g} gf·cm/cm"
)

# %%
# The fit against the data
# ------------------------
# Left, KES-FB1: the loading branch is what the quartic is fitted to (the unloading
# branch is the energy returned, RT); the true law is dashed. Right, KES-FB2: the model's
# moment along the measured curvature path, run through the simulation kernel's own hinge
# law, over the measured loop. The loop's width at K = ±1 1/cm is 2HB, the slope of its
# branches B, the two numbers a KES-FB2 chart reports.
strain = np.linspace(0, tensile.strain.max(), 200)
a = truth["tensile_gf_per_cm"]
true_force = strain * (a[0] + strain * (a[1] + strain * (a[2] + strain * a[3])))
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.3))
left.plot(tensile.strain * 100, tensile.force, ".", ms=3, color="0.5", label="KES-FB1 data")
left.plot(strain * 100, fit.tensile(strain), "C3", lw=1.5, label="fitted quartic")
left.plot(strain * 100, true_force, "k--", lw=0.8, label="true law")
left.set(
    xlabel="strain ε (%)",
    ylabel="force per width T (gf/cm)",
    title=f"tensile: EMT {tk.emt_percent:.3g} %, LT {tk.lt:.3g}, RT {tk.rt_percent:.3g} %",
)
left.legend(fontsize=8)
right.plot(bending.curvature, bending.moment, ".", ms=3, color="0.5", label="KES-FB2 data")
right.plot(bending.curvature, b.moment, "C3", lw=1.2, label="fitted law along the path")
right.axhline(0, color="0.8", lw=0.5)
right.axvline(0, color="0.8", lw=0.5)
right.set(
    xlabel="curvature K (1/cm)",
    ylabel="moment per width M (gf·cm/cm)",
    title=f"bending: B {bk.b_gf_cm2_per_cm:.3g} gf·cm²/cm, 2HB {bk.hb2_gf_cm_per_cm:.3g} gf·cm/cm",
)
right.legend(fontsize=8)
fig.tight_layout()

# %%
# The material file
# -----------------
# KES data do not contain the mass per area: it is weighed and given (here the default
# material's 2.03e-2 g/cm²). The file holds a ``[material]`` table a scene reads with
# ``material.from_file``, and a ``[fit]`` table with the verdict, residuals and KES values.
data = kes.material_file_data(
    fit,
    "wool-fitted",
    2.03e-2,
    source="fitted in examples/plot_kes_fit.py to the bundled kes_fb1_example and kes_fb2_example",
)
path = kes.write_material_file(workdir / "wool-fitted.toml", data)
print(path.read_text())

# %%
# The fitted material in a swing
# ------------------------------
# A scene uses the file with ``material.from_file``; the damped swing with the fitted
# material against the same swing with the true one shows what the fit's small errors
# cost in the motion. (``WARPCLOTH_EXAMPLES_QUICK=1`` records 1 s instead of 3 s.)
duration = {"run.duration_s": 1.0} if QUICK else {}
for label, material in (("true material", "wool90-nylon10"), ("fitted material", str(path))):
    run = wc.run("damped_swing", {"material.from_file": material} | duration)
    swing = swing_summary(run.t, run.probe("laser_x", 0))
    print(
        f"{label:>16}: first period {swing['first_period_s']:.4f} s, "
        f"first amplitude {swing['first_amplitude_m'] * 1e3:.2f} mm"
    )
shutil.rmtree(workdir)
plt.show()
