# A ready ParaView view of an efgdem run (written by `efgdem view OUT`).
#
#   paraview --script=OUT/view.py                 # the GUI, last frame shown
#   pvbatch OUT/view.py --screenshot view.png     # an image (headless:
#                                                 # xvfb-run pvbatch ...)
#     options: --time T (default: the last frame), --size W H,
#              --discs displacement (colour the discs by their displacement
#              since t = 0 instead of their speed)
#
# Discs are true-size filled circles coloured by speed, bodies (deformed)
# coloured by von Mises stress, contact force chains are tubes whose width
# grows with the normal force, walls are black lines, and the time is shown.
# Tested with ParaView 5.11.
import glob
import os
import sys

import paraview.simple
from paraview.simple import *  # noqa: F401,F403

paraview.simple._DisableFirstRenderCameraReset()  # the camera is set below

# the run's directory: next to this script (the path below if ParaView runs
# it without __file__)
try:
    HERE = os.path.dirname(os.path.abspath(__file__))
except NameError:
    HERE = r"@DIR@"


def option(name, n=1):
    """The value(s) after command-line flag `name`, or None."""
    if name not in sys.argv:
        return None
    k = sys.argv.index(name)
    v = sys.argv[k + 1:k + 1 + n]
    return v[0] if n == 1 else v


SCREENSHOT = option("--screenshot")
AT = option("--time")
SIZE = [int(x) for x in (option("--size", 2) or [1600, 900])]
DISC_FIELD = option("--discs") or "velocity"
if DISC_FIELD not in ("velocity", "displacement"):
    raise SystemExit("--discs: velocity or displacement")

pvd = {os.path.basename(p)[:-4]: p for p in sorted(glob.glob(os.path.join(HERE, "*.pvd")))}
static = sorted(glob.glob(os.path.join(HERE, "*.vtu")))
if not pvd and not static:
    raise SystemExit("no efgdem frames (*.pvd, *.vtu) in " + HERE)

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


def colour_bar(display, lut, title):
    bar = GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.TitleColor = BLACK
    bar.LabelColor = BLACK
    bar.TitleFontSize = 14
    bar.LabelFontSize = 12
    bar.ScalarBarLength = 0.3
    bar.AutomaticLabelFormat = 0
    bar.LabelFormat = "%-.3g"
    bar.RangeLabelFormat = "%-.3g"
    display.SetScalarBarVisibility(view, True)
    return bar


bars = []

# bodies, deformed (points at X + u); colour: von Mises stress
bodies = [(n, p) for n, p in pvd.items() if n not in ("discs", "contacts", "walls")]
body_files = [(n, PVDReader(registrationName=n, FileName=p)) for n, p in bodies]
body_files += [
    (os.path.basename(p)[:-4], XMLUnstructuredGridReader(registrationName=os.path.basename(p), FileName=[p]))
    for p in static
]
behind = []
for name, src in body_files:
    src = Transform(registrationName=name + " (behind)", Input=src)
    behind.append(src)
    d = Show(src, view)
    d.SetRepresentationType("Surface With Edges")
    d.EdgeColor = [0.35, 0.35, 0.35]
    ColorBy(d, ("POINTS", "von_mises"))
    lut = GetColorTransferFunction("von_mises")
    lut.ApplyPreset("Turbo", True)
    if not bars or bars[-1][1] is not lut:
        bars.append((d, lut, "von Mises stress [Pa]"))

# walls: black lines
if "walls" in pvd:
    walls = PVDReader(registrationName="walls", FileName=pvd["walls"])
    d = Show(walls, view)
    d.ColorArrayName = ["POINTS", ""]
    d.AmbientColor = d.DiffuseColor = BLACK
    d.LineWidth = 3.0
    d.RenderLinesAsTubes = 1

# discs: true-size filled circles (point Gaussians of radius `radius`)
# coloured by speed
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
    bars.append((d, lut, "disc speed [m/s]" if DISC_FIELD == "velocity" else "disc displacement [m]"))

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

# time: the last frame unless --time
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
times = list(GetTimeKeeper().TimestepValues or [])
if AT is not None:
    scene.AnimationTime = float(AT)
elif times:
    scene.AnimationTime = times[-1]

# sizes: tubes from the smallest disc radius (or 1/200 of the scene)
view.ResetCamera(False)
bounds = None
for s in GetSources().values():
    try:
        b = s.GetDataInformation().GetBounds()
    except AttributeError:
        continue
    if b and b[0] <= b[1]:
        bounds = b if bounds is None else [
            min(bounds[0], b[0]), max(bounds[1], b[1]), min(bounds[2], b[2]), max(bounds[3], b[3]), 0, 0]
if bounds and "discs" in pvd:  # the discs' centres, plus their radii
    r = discs.PointData["radius"].GetRange()
    if r[0] <= r[1]:
        bounds = [bounds[0] - r[1], bounds[1] + r[1], bounds[2] - r[1], bounds[3] + r[1], 0, 0]
extent = max(bounds[1] - bounds[0], bounds[3] - bounds[2]) if bounds else 1.0
if "contacts" in pvd:
    rmin = extent / 200.0
    if "discs" in pvd:
        r = discs.PointData["radius"].GetRange()
        if r[0] <= r[1] and r[0] > 0:
            rmin = r[0]
    tubes.Radius = 0.08 * rmin
    tubes.RadiusFactor = 5.0
    chains.Transform.Translate = [0.0, 0.0, 0.01 * extent]
for b in behind:
    b.Transform.Translate = [0.0, 0.0, -0.01 * extent]

if pvd:  # a static analysis has no time
    title = AnnotateTime(registrationName="time")
    title.Format = "t = {time:.6g} s"
    td = Show(title, view)
    td.Color = BLACK
    td.FontSize = 20
    td.WindowLocation = "Upper Left Corner"

# colour bars along the bottom; speed and displacement from 0
for k, (d, lut, name) in enumerate(bars):
    bar = colour_bar(d, lut, name)
    bar.WindowLocation = "Any Location"
    bar.Orientation = "Horizontal"
    bar.Position = [0.06 + 0.5 * k, 0.03]
    d.RescaleTransferFunctionToDataRange(False, True)
    if name.startswith("disc "):
        lo, hi = d.LookupTable.RGBPoints[0], d.LookupTable.RGBPoints[-4]
        lut.RescaleTransferFunction(0.0, hi if hi > 0 else 1.0)

# the scene fills the band between the colour bars and the time
view.ResetCamera(False)
if bounds:
    w, h = bounds[1] - bounds[0], bounds[3] - bounds[2]
    size = list(view.ViewSize) if not SCREENSHOT else SIZE
    aspect = size[0] / float(max(size[1], 1))
    band_lo, band_hi = 0.2, 0.93  # fractions of the image height
    scale = 0.5 * max(h / (band_hi - band_lo), w / (0.94 * aspect), 1e-12)
    cx, cy = 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3])
    cy -= (0.5 * (band_lo + band_hi) - 0.5) * 2.0 * scale
    view.CameraPosition = [cx, cy, extent * 10.0]
    view.CameraFocalPoint = [cx, cy, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 1
    view.CameraParallelScale = scale
Render(view)

if SCREENSHOT:
    SaveScreenshot(SCREENSHOT, view, ImageResolution=SIZE, TransparentBackground=0)
    print("wrote " + SCREENSHOT)
