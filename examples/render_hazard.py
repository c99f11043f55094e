"""Renders the hazard of a `glint run` as a PNG with ParaView:

    HWLOC_COMPONENTS=-gl xvfb-run -a -s "-noreset" pvpython examples/render_hazard.py OUT_DIR
             [--level W_M2 | --ratio R] [--png FILE] [--size WIDTH HEIGHT]

(Debian's ParaView renders through X; xvfb-run gives it a virtual display on a machine
without one. On a desktop, plain `pvpython` will do.)

OUT_DIR is the folder `glint run` wrote. The picture shows the surface where the hazard ratio
(irradiance / MPE) is 1, the boundary of the nominal hazard zone: every point inside it
receives more than the MPE. `--ratio R` draws another ratio, `--level W_M2` an irradiance
instead; where no point reaches the MPE the default falls back to 10 % of the peak irradiance
and says so. The target is coloured by the beam power each facet receives, inside the box
outline. Default PNG: OUT_DIR/hazard.png.
"""
import argparse
import json
import os
import sys

from paraview.simple import (
    ColorBy,
    Contour,
    CreateView,
    GetColorTransferFunction,
    OpenDataFile,
    Outline,
    Render,
    ResetCamera,
    SaveScreenshot,
    Show,
)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir")
    choice = parser.add_mutually_exclusive_group()
    choice.add_argument("--level", type=float, help="irradiance of the surface, W/m^2")
    choice.add_argument("--ratio", type=float, help="hazard ratio of the surface (default 1)")
    parser.add_argument("--png", help="picture to write (default OUT_DIR/hazard.png)")
    parser.add_argument("--size", type=int, nargs=2, default=[1280, 800])
    args = parser.parse_args()

    summary = json.load(open(os.path.join(args.out_dir, "summary.json")))
    peak = summary["peak_irradiance_w_m2"]
    peak_ratio = summary["hazard"]["peak_hazard_ratio"]
    if args.level is not None:
        array, level, unit, peak_value = "irradiance_w_m2", args.level, "W/m^2", peak
    elif args.ratio is not None or peak_ratio >= 1.0:
        array, level, unit, peak_value = "hazard_ratio", args.ratio or 1.0, "x MPE", peak_ratio
    else:
        print(f"render_hazard: no point reaches the MPE (peak hazard ratio {peak_ratio:.3g}); "
              "drawing 10 % of the peak irradiance instead")
        array, level, unit, peak_value = "irradiance_w_m2", 0.1 * peak, "W/m^2", peak
    if not level > 0.0:
        sys.exit(f"render_hazard: level {level} {unit} must be > 0 (peak {peak_value} {unit})")
    png = args.png or os.path.join(args.out_dir, "hazard.png")

    view = CreateView("RenderView")
    view.ViewSize = args.size
    view.OrientationAxesVisibility = 1

    volume = OpenDataFile(os.path.join(args.out_dir, "irradiance.vti"))
    Show(Outline(Input=volume), view).DiffuseColor = [0.3, 0.3, 0.3]

    contour = Contour(Input=volume, ContourBy=["POINTS", array], Isosurfaces=[level])
    contour.ComputeNormals = 1
    contour.UpdatePipeline()
    if contour.GetDataInformation().GetNumberOfPoints() == 0:
        sys.exit(f"render_hazard: nothing reaches {level:.4g} {unit} (peak {peak_value:.4g})")
    surface = Show(contour, view)
    ColorBy(surface, None)
    surface.DiffuseColor = [0.85, 0.15, 0.1]
    surface.Opacity = 0.45

    target = OpenDataFile(os.path.join(args.out_dir, "target.vtp"))
    shown = Show(target, view)
    ColorBy(shown, ("CELLS", "incident_power_w"))
    GetColorTransferFunction("incident_power_w").ApplyPreset("Grayscale", True)
    shown.SetScalarBarVisibility(view, True)

    # Oblique from the laser's side and above, where the reflected light of most scenes goes.
    view.CameraPosition = [-1.0, -1.6, 1.1]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    ResetCamera(view)
    Render(view)
    SaveScreenshot(png, view, ImageResolution=args.size)

    # A picture of one colour means nothing was drawn (no surface, no target in view).
    from vtkmodules.vtkIOImage import vtkPNGReader

    reader = vtkPNGReader()
    reader.SetFileName(png)
    reader.Update()
    lo, hi = reader.GetOutput().GetPointData().GetScalars().GetRange(0)
    if not hi > lo:
        sys.exit(f"render_hazard: {png} is blank")
    print(f"{png}: surface of {array} at {level:.4g} {unit} (peak {peak_value:.4g} {unit})")


if __name__ == "__main__":
    main()
