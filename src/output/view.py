# A ready ParaView view of an efgdem run (written by `efgdem view OUT`).
#
#   paraview --script=OUT/view.py                 # the GUI
#   pvbatch OUT/view.py --screenshot view.png     # an image (without a
#                                                 # display: efgdem view OUT
#                                                 # --screenshot view.png)
# options (their defaults are those `efgdem view` was given):
#   --time T            the frame shown (default: the last)
#   --size W H          image size in pixels
#   --discs velocity|displacement
#                       colour the discs by their speed or by their
#                       displacement since t = 0
#   --range series|frame
#                       colour ranges over all frames (stay put when you
#                       step through time) or each frame's own
#   --percentile P      the discs' colour range ends at the P-th percentile
#                       of their values (faster discs saturate), 100: the
#                       largest
#   --region X0 Y0 X1 Y1
#                       show this rectangle only (zoom into a large bed)
#   --edges auto|on|off body grid lines (auto: only where cells are at
#                       least 6 pixels wide)
#   --warp F            show the bodies' displacements F times (1: true)
#
# Discs are true-size filled circles, bodies deformed and coloured by von
# Mises stress, contact force chains are tubes whose width grows with the
# normal force, walls are black lines, and the time is shown. Tested with
# ParaView 5.11.
import glob
import json
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import paraview.simple
from paraview.simple import *  # noqa: F401,F403
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader

paraview.simple._DisableFirstRenderCameraReset()  # the camera is set below

# the run's directory: next to this script (the path below if ParaView runs
# it without __file__)
try:
    HERE = os.path.dirname(os.path.abspath(__file__))
except NameError:
    HERE = r"@DIR@"

DEFAULTS = json.loads(r"""@OPTIONS@""")


def option(name, n=1):
    """The value(s) after command-line flag `--name`, else the default."""
    flag = "--" + name
    if flag not in sys.argv:
        return DEFAULTS.get(name)
    k = sys.argv.index(flag)
    v = sys.argv[k + 1:k + 1 + n]
    return v[0] if n == 1 else v


SCREENSHOT = option("screenshot")
AT = option("time")
SIZE = [int(x) for x in (option("size", 2) or [1600, 900])]
DISC_FIELD = option("discs") or "velocity"
RANGE = option("range") or "series"
PERCENTILE = float(option("percentile") or 99.0)
REGION = [float(x) for x in option("region", 4)] if option("region", 4) else None
EDGES = option("edges") or "auto"
WARP = float(option("warp") or 1.0)
for name, value, allowed in (("discs", DISC_FIELD, ("velocity", "displacement")),
                             ("range", RANGE, ("series", "frame")),
                             ("edges", EDGES, ("auto", "on", "off"))):
    if value not in allowed:
        raise SystemExit("--%s: %s" % (name, " or ".join(allowed)))
if not 0.0 < PERCENTILE <= 100.0:
    raise SystemExit("--percentile: in (0, 100]")

pvd = {os.path.basename(p)[:-4]: p for p in sorted(glob.glob(os.path.join(HERE, "*.pvd")))}
static = sorted(glob.glob(os.path.join(HERE, "*.vtu")))
if not pvd and not static:
    raise SystemExit("no efgdem frames (*.pvd, *.vtu) in " + HERE)


def frames(path):
    """(time, file) of every frame of a .pvd series."""
    root = ET.parse(path).getroot()
    d = os.path.dirname(path)
    return [(float(e.get("timestep")), os.path.join(d, e.get("file")))
            for e in root.iter("DataSet")]


def read(path):
    """A frame file as a VTK data object."""
    r = vtkXMLPolyDataReader() if path.endswith(".vtp") else vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def inside(points):
    """Mask of the points in --region (all without one)."""
    if REGION is None:
        return np.ones(len(points), dtype=bool)
    x, y = points[:, 0], points[:, 1]
    return (x >= REGION[0]) & (x <= REGION[2]) & (y >= REGION[1]) & (y <= REGION[3])


def values(data, name):
    """Magnitudes of point array `name` of the points in --region."""
    a = vtk_to_numpy(data.GetPointData().GetArray(name))
    if a.ndim > 1:
        a = np.linalg.norm(a, axis=1)
    return a[inside(vtk_to_numpy(data.GetPoints().GetData()))]


def value_range(files, name, percentile):
    """(low, high) of array `name` over `files`: the smallest value and the
    `percentile`-th percentile, pooled over the frames."""
    v = [values(read(f), name) for f in files]
    v = np.concatenate([a for a in v if len(a)] or [np.zeros(1)])
    return float(v.min()), float(np.percentile(v, percentile))


view = GetActiveViewOrCreate("RenderView")
if SCREENSHOT:
    view.ViewSize = SIZE
view.OrientationAxesVisibility = 0
view.InteractionMode = "2D"
try:  # ParaView ≥ 5.10: the background is not taken from the palette
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.Background = [1.0, 1.0, 1.0]
BLACK = [0.0, 0.0, 0.0]

# the time shown: the last frame unless --time
scene = GetAnimationScene()
series = [frames(p) for p in pvd.values()]
times = sorted({t for s in series for t, _ in s})
now = float(AT) if AT is not None else (times[-1] if times else 0.0)


def shown(fs):
    """The files of frames `fs` (time, file) a colour range is taken over:
    all of them (--range series), or the one shown (--range frame)."""
    if RANGE == "series":
        return [f for _, f in fs]
    return [min(fs, key=lambda tf: abs(tf[0] - now))[1]]


# (display, lookup table, title, (low, high))
bars = []
# [(source, cells)] of the bodies, for the grid lines
body_sources = []

# bodies, deformed (points at X + u; × --warp); colour: von Mises stress
bodies = [(n, p) for n, p in pvd.items() if n not in ("discs", "contacts", "walls")]
body_files = [(n, PVDReader(registrationName=n, FileName=p), frames(p)) for n, p in bodies]
body_files += [
    (os.path.basename(p)[:-4],
     XMLUnstructuredGridReader(registrationName=os.path.basename(p), FileName=[p]), [(0.0, p)])
    for p in static
]
behind = []
stress_files = []
for name, src, files in body_files:
    if WARP != 1.0:
        src = WarpByVector(registrationName=name + " (warped)", Input=src)
        src.Vectors = ["POINTS", "displacement"]
        src.ScaleFactor = WARP - 1.0
    src = Transform(registrationName=name + " (behind)", Input=src)
    behind.append(src)
    d = Show(src, view)
    d.SetRepresentationType("Surface")
    d.EdgeColor = [0.35, 0.35, 0.35]
    ColorBy(d, ("POINTS", "von_mises"))
    lut = GetColorTransferFunction("von_mises")
    lut.ApplyPreset("Turbo", True)
    body_sources.append((d, read(files[-1][1])))
    stress_files += shown(files)
    if not any(b[1] is lut for b in bars):
        title = "von Mises stress [Pa]" + ("; displacements ×%g" % WARP if WARP != 1.0 else "")
        bars.append([d, lut, title, None])
if stress_files:
    bars[0][3] = value_range(stress_files, "von_mises", 100.0)

# walls: black lines
if "walls" in pvd:
    walls = PVDReader(registrationName="walls", FileName=pvd["walls"])
    d = Show(walls, view)
    d.ColorArrayName = ["POINTS", ""]
    d.AmbientColor = d.DiffuseColor = BLACK
    d.LineWidth = 3.0
    d.RenderLinesAsTubes = 1

# discs: true-size filled circles (point Gaussians of radius `radius`)
# coloured by speed or displacement, from 0 to the --percentile over the
# frames of --range
if "discs" in pvd:
    discs = PVDReader(registrationName="discs", FileName=pvd["discs"])
    d = Show(discs, view)
    d.SetRepresentationType("Point Gaussian")
    d.ShaderPreset = "Plain circle"
    d.ScaleByArray = 1
    d.SetScaleArray = ["POINTS", "radius"]
    d.UseScaleFunction = 0
    d.GaussianRadius = 1.0
    ColorBy(d, ("POINTS", DISC_FIELD, "Magnitude"))
    lut = GetColorTransferFunction(DISC_FIELD)
    lut.ApplyPreset("Cool to Warm", True)
    _, hi = value_range(shown(frames(pvd["discs"])), DISC_FIELD, PERCENTILE)
    what = "disc speed [m/s]" if DISC_FIELD == "velocity" else "disc displacement [m]"
    if PERCENTILE < 100.0:
        what += ", %g%% below" % PERCENTILE
    bars.append([d, lut, what, (0.0, hi)])

# contact force chains: tubes along the contact lines, wider with larger
# normal force (a tube's radius goes from `Radius` at the smallest force
# of the frame to `RadiusFactor` × it at the largest); in front of the discs
if "contacts" in pvd:
    contacts = PVDReader(registrationName="contacts", FileName=pvd["contacts"])
    onpts = CellDatatoPointData(registrationName="contacts (point data)", Input=contacts)
    tubes = Tube(registrationName="force chains", Input=onpts)
    tubes.Scalars = ["POINTS", "fn"]
    tubes.VaryRadius = "By Scalar"
    tubes.NumberofSides = 8
    chains = Transform(registrationName="force chains (front)", Input=tubes)
    d = Show(chains, view)
    d.ColorArrayName = ["POINTS", ""]
    d.AmbientColor = d.DiffuseColor = BLACK

scene.UpdateAnimationUsingDataTimeSteps()
if times:
    scene.AnimationTime = now

# what is shown: --region, or every dataset's bounds (discs with radii)
bounds = None
for s in GetSources().values():
    try:
        b = s.GetDataInformation().GetBounds()
    except AttributeError:
        continue
    if b and b[0] <= b[1]:
        bounds = b if bounds is None else [
            min(bounds[0], b[0]), max(bounds[1], b[1]), min(bounds[2], b[2]), max(bounds[3], b[3]), 0, 0]
rmin, rmax = None, None
if "discs" in pvd:
    r = discs.PointData["radius"].GetRange()
    if r[0] <= r[1]:
        rmin, rmax = r
        if bounds:
            bounds = [bounds[0] - rmax, bounds[1] + rmax, bounds[2] - rmax, bounds[3] + rmax, 0, 0]
if REGION is not None:
    bounds = [REGION[0], REGION[2], REGION[1], REGION[3], 0, 0]
extent = max(bounds[1] - bounds[0], bounds[3] - bounds[2]) if bounds else 1.0

# the camera: the scene fills the band between the colour bars and the time
size = SIZE if SCREENSHOT else list(view.ViewSize)
band_lo, band_hi = 0.2, 0.93  # fractions of the image height
scale = 1.0
if bounds:
    w, h = bounds[1] - bounds[0], bounds[3] - bounds[2]
    aspect = size[0] / float(max(size[1], 1))
    scale = 0.5 * max(h / (band_hi - band_lo), w / (0.94 * aspect), 1e-12)
    cx, cy = 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3])
    cy -= (0.5 * (band_lo + band_hi) - 0.5) * 2.0 * scale
    view.CameraPosition = [cx, cy, extent * 10.0]
    view.CameraFocalPoint = [cx, cy, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 1
    view.CameraParallelScale = scale
pixel = 2.0 * scale / max(size[1], 1)  # world length of a pixel

# tubes from the smallest disc radius (or 1/200 of the scene), at least a
# pixel wide
if "contacts" in pvd:
    tubes.Radius = max(0.08 * (rmin if rmin else extent / 200.0), 0.5 * pixel)
    tubes.RadiusFactor = 5.0
    chains.Transform.Translate = [0.0, 0.0, 0.01 * extent]
for b in behind:
    b.Transform.Translate = [0.0, 0.0, -0.01 * extent]

# body grid lines: on, off, or where a cell is at least 6 pixels wide
for d, data in body_sources:
    cells = max(data.GetNumberOfCells(), 1)
    b = data.GetBounds()
    cell = ((b[1] - b[0]) * (b[3] - b[2]) / cells) ** 0.5
    edges = EDGES == "on" or (EDGES == "auto" and cell >= 6.0 * pixel)
    d.SetRepresentationType("Surface With Edges" if edges else "Surface")

if pvd:  # a static analysis has no time
    title = AnnotateTime(registrationName="time")
    title.Format = "t = {time:.6g} s"
    td = Show(title, view)
    td.Color = BLACK
    td.FontSize = 20
    td.WindowLocation = "Upper Left Corner"

# colour bars along the bottom, their ranges fixed (--range series: the
# same in every frame) or following each frame (--range frame, the GUI)
for k, (d, lut, name, rng) in enumerate(bars):
    bar = GetScalarBar(lut, view)
    bar.Title = name
    bar.ComponentTitle = ""
    bar.TitleColor = BLACK
    bar.LabelColor = BLACK
    bar.TitleFontSize = 14
    bar.LabelFontSize = 12
    bar.ScalarBarLength = 0.3
    bar.AutomaticLabelFormat = 0
    bar.LabelFormat = "%-.3g"
    bar.RangeLabelFormat = "%-.3g"
    bar.WindowLocation = "Any Location"
    bar.Orientation = "Horizontal"
    bar.Position = [0.06 + 0.5 * k, 0.03]
    try:  # over a scene that reaches under the bar (a --region)
        bar.DrawBackground = 1
        bar.BackgroundColor = [1.0, 1.0, 1.0, 0.85]
    except AttributeError:
        pass
    d.SetScalarBarVisibility(view, True)
    lo, hi = rng if rng else (0.0, 1.0)
    if hi <= lo:
        hi = lo + (abs(lo) if lo else 1.0)
    lut.RescaleTransferFunction(lo, hi)
    lut.AutomaticRescaleRangeMode = "Never" if RANGE == "series" or SCREENSHOT else "Clamp and update every timestep"
    if SCREENSHOT:  # what the colours of the image mean
        print("colours: %s: %.9g to %.9g" % (name, lo, hi))

Render(view)

if SCREENSHOT:
    SaveScreenshot(SCREENSHOT, view, ImageResolution=SIZE, TransparentBackground=0)
    print("wrote " + SCREENSHOT)
