"""Render one snapshot of a run's .xmf (written by `rbc-sweep --xdmf`) to a PNG with ParaView.

    xvfb-run -a pvpython scripts/render_xmf.py FILE.xmf OUT.png [TIME_S]

(`xvfb-run -a` only where there is no display; Debian's `xvfb` package.) The mesh is read by
ParaView's XDMF Reader, the reader users open the file with; TIME_S defaults to the last snapshot.
The camera looks at the cell from upstream, the side and above (x downstream, z up; the axes
triad in the corner: x red, y yellow, z green).
"""
import sys

from paraview.simple import (GetActiveViewOrCreate, Render, SaveScreenshot, Show, Text,
                             XDMFReader)


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: pvpython scripts/render_xmf.py FILE.xmf OUT.png [TIME_S]")
    xmf, out = sys.argv[1], sys.argv[2]
    r = XDMFReader(FileNames=[xmf])
    tv = r.TimestepValues
    times = [tv] if isinstance(tv, float) else list(tv)
    t = float(sys.argv[3]) if len(sys.argv) == 4 else times[-1]
    v = GetActiveViewOrCreate("RenderView")
    v.ViewSize = [900, 600]
    v.ViewTime = t
    v.UseColorPaletteForBackground = 0
    v.Background = [1, 1, 1]
    v.OrientationAxesVisibility = 1
    v.OrientationAxesLabelColor = [0, 0, 0]
    d = Show(r, v)
    d.DiffuseColor = [0.8, 0.2, 0.2]
    d.Specular = 0.3
    name = xmf.rsplit("/", 1)[-1]
    label = Show(Text(Text=f"{name}\nt = {t * 1e3:g} ms (XDMF Reader)"), v)
    label.Color = [0, 0, 0]
    label.FontSize = 14
    v.CameraPosition = [-20, -30, 20]
    v.CameraViewUp = [0, 0, 1]
    v.ResetCamera()
    Render(v)
    SaveScreenshot(out, v, ImageResolution=[900, 600])
    print(f"{out}: t = {t} s")


if __name__ == "__main__":
    main()
