"""Writes the instrument-layout fixtures of tests/data (our own numbers, from a structural-damping law)."""
import math
from pathlib import Path
import numpy as np

OUT = Path(__file__).parent
ALPHA, ETA = 0.2, 0.05


RNG = np.random.default_rng(20)


def law(w, G0):
    """The law with 2 % multiplicative scatter, as a measurement has."""
    Gp = G0 * w ** ALPHA * math.cos(ALPHA * math.pi / 2) * math.exp(0.02 * RNG.standard_normal())
    Gl = (G0 * w ** ALPHA * math.sin(ALPHA * math.pi / 2) + ETA * w) * math.exp(0.02 * RNG.standard_normal())
    return Gp, Gl


def g(x):  # TRIOS writes up to 15 significant digits, E notation for small numbers
    return repr(float(x)).replace("e-0", "E-0").replace("e-", "E-").replace("e+", "E+")


# ---- 1. TRIOS LIMS: three frequency sweeps at 37, 25, 15 °C, moduli in MPa ------------------------
w = np.logspace(np.log10(0.628318548202515), np.log10(62.8318557739258), 9)
variables = ["Run time", "Temperature", "Angular frequency", "Oscillation torque", "Oscillation strain",
             "Oscillation stress", "Step time", "Phase angle", "Status bits", "Date and time", "Frequency",
             "Tan(delta)", "Complex modulus", "Storage modulus", "Loss modulus", "Storage compliance"]
unitrow = ["s", "°C", "rad/s", "µN.m", "%", "MPa", "s", "°", "", "", "Hz", "", "MPa", "MPa", "MPa", "1/MPa"]
lines = ["[Version]", "TA Instruments LIMS export format version\t0", "[Header]", "Document ID\tlab-demo",
         "Instrument serial number\t4010-0000", "Instrument name\tDemo rheometer", "Logged-in user at run start\tLab",
         "Run date\t01/02/2026", "[Sample]", "Name\tHASM monolayer (synthetic)", "Operator\tLab",
         "Notes\tWritten by tenscell's tests from a structural-damping law; not an instrument recording",
         "[Geometry]", "[Geometry: Standard]", "Name\t8 mm parallel plate", "Diameter\t8.0 mm", "Gap\t0.500000 mm",
         "[Procedure: Steps]", "Step 1\tConditioning-Sample : Temperature 37 °C Soak Time 120.0 s",
         "Step 2\tOscillation-Temperature Sweep : Start temperature 37 °C End temperature 15 °C Frequency 0.1 to 10Hz",
         "[Parameters]", "[Parameters: File Parameters]", "Name\tdemo.tri", "Trios version\t5.1.1.46572",
         "[Parameters: Instrument Parameters]", "GapZeroSetback\t1.000 [mm]"]
t = 100.0
for T, G0 in ((37.0, 80.0), (25.0, 120.0), (15.0, 200.0)):
    lines += ["[Step]", f"Step name\tFrequency sweep ({T:.1f} °C)", f"Number of points\t{w.size}",
              "Variables\t" + "\t".join(variables), "Units\t" + "\t".join(unitrow) + "\t"]
    Gp, Gl = law(w, G0)
    for k, (wi, a, b) in enumerate(zip(w, Gp, Gl)):
        t += 7.25
        Gs = math.hypot(a, b)
        row = [t, T + 0.01 * (-1) ** k, wi, 12.5 * Gs / 100, 1.0, Gs * 1e-2 / 1e6, 3.0 * k, math.degrees(math.atan2(b, a)),
               "0", "01/02/2026 10:00:00", wi / (2 * math.pi), b / a, Gs / 1e6, a / 1e6, b / 1e6, 1e6 * a / Gs ** 2]
        lines.append("Data point\t" + "\t".join(x if isinstance(x, str) else g(x) for x in row) + "\t")
(OUT / "trios_lims_temperature_steps.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")

# ---- 2. TRIOS plain text: amplitude sweep, frequency sweep (kPa), creep (min, 1/MPa) ----------------------
meta = ["Filename\tdemo_cells", "Instrument name\tDemo rheometer", "Operator\tLab", "rundate\t01/02/2026",
        "Sample name\tfibroblast layer (synthetic)", "Geometry name\t8 mm parallel plate", "Procedure name\tdemo",
        "\tAmplitude sweep", "\tFrequency sweep", "\tCreep", "proceduresegments\tAmplitude sweep#Frequency sweep#Creep",
        "[File Parameters]", "Name\tdemo_cells", "Trios version\t5.1.1.46572", "[Geometry Parameters]",
        "Geometry Type\tParallel plate", "Diameter\t8 mm"]
names = ["Angular frequency", "Step time", "Temperature", "Oscillation strain", "Storage modulus", "Loss modulus",
         "Tan(delta)", "Date and time", "Frequency"]
units = ["rad/s", "min", "°C", "%", "kPa", "kPa", "", "", "Hz"]
out = list(meta)
out += ["", "[step]", "Amplitude sweep - 1", "\t".join(names) + "\t", "\t".join(units) + "\t"]
for k, strain in enumerate(np.logspace(-1, 1, 5)):
    a, b = law(6.283185307179586, 150.0)
    out.append("\t".join(g(x) if not isinstance(x, str) else x for x in
                         [6.283185307179586, 0.1 * (k + 1), 37.0, strain, a / 1e3, b / 1e3, b / a,
                          "01/02/2026 11:00:00", 1.0]) + "\t")
out += ["", "[step]", "Frequency sweep - 2", "\t".join(names) + "\t", "\t".join(units) + "\t"]
for k, wi in enumerate(w[::-1]):
    a, b = law(wi, 150.0)
    out.append("\t".join(g(x) if not isinstance(x, str) else x for x in
                         [wi, 0.1 * (k + 1), 37.0, 1.0, a / 1e3, b / 1e3, b / a, "01/02/2026 11:05:00",
                          wi / (2 * math.pi)]) + "\t")
(OUT / "trios_text_steps.txt").write_text("\n".join(out) + "\n", encoding="utf-8")

cnames = ["Torque", "Step time", "Temperature", "Time", "Stress", "Strain", "Date and time", "Compliance", "Modulus"]
cunits = ["µN.m", "min", "°C", "min", "Pa", "%", "", "1/MPa", "MPa"]
tmin = np.concatenate([[0.0], np.logspace(-3, 0.5, 12)])  # minutes; the first point is the step's onset
J0, BETA = 2.0e-3, 0.25  # 1/Pa at 1 s, power-law exponent
out = list(meta[:7]) + ["", "[step]", "Creep - 3", "\t".join(cnames) + "\t", "\t".join(cunits) + "\t"]
for tm in tmin:
    J = 0.0 if tm == 0 else J0 * (60 * tm) ** BETA * math.exp(0.02 * RNG.standard_normal())
    out.append("\t".join(g(x) if not isinstance(x, str) else x for x in
                         [15.0, tm, 37.0, tm, 10.0, 100 * 10.0 * J, "01/02/2026 11:30:00", J * 1e6,
                          (1 / J / 1e6) if J else 0.0]) + "\t")
(OUT / "trios_text_creep.txt").write_text("\n".join(out) + "\n", encoding="utf-8")

# ---- 3. RheoCompass, short headers, no leading empty field, one interval ------------------------------
rc = ["Project:\tcells_2026", "Test:\tFS_fibroblast_37C", "Result:\tFS_fibroblast_37C 1", "Date:\t2026-02-01",
      "Operator:\tLab", "Measuring System:\tPP08", "Temperature:\t37.0 °C", "", "Interval and data points:\t1\t10",
      "Test Type:\tOscillation", "Interval data:\tω\tG'\tG''\t|G*|\tδ",
      "\t[rad/s]\t[Pa]\t[Pa]\t[Pa]\t[°]"]
wr = np.logspace(-1, 2, 10)
for wi in wr:
    a, b = law(wi, 60.0)
    rc.append("\t".join(f"{x:.5g}" for x in (wi, a, b, math.hypot(a, b), math.degrees(math.atan2(b, a)))))
(OUT / "rheocompass_short_headers.txt").write_text("\n".join(rc) + "\n", encoding="utf-8")

# ---- 4. tab-separated creep table with a units row ----------------------------------------------------
ts = np.logspace(-2, 2, 15)
cr = ["Time\tCreep Compliance", "[s]\t[1/Pa]"] + [f"{x:.6g}\t{J0 * x ** BETA * math.exp(0.02 * RNG.standard_normal()):.6g}" for x in ts]
(OUT / "creep_compliance.tsv").write_text("\n".join(cr) + "\n", encoding="utf-8")
print("ok")
