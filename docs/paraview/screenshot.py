# A headless ParaView screenshot of a FEKAP run (docs/paraview.md):
#   xvfb-run -a pvpython docs/paraview/screenshot.py OUT/<stem>.pvd shot.png
# the reference configuration in grey, Warp By Vector (displacement, scale 1) at 30 % of the run coloured by |displacement|.
import sys
from paraview.simple import *
reader = PVDReader(FileName=sys.argv[1])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues)
view = CreateView("RenderView")
view.ViewSize = [900, 700]
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except Exception:
    pass
view.OrientationAxesVisibility = 0
ref = Show(reader, view)
ref.DiffuseColor = [0.75, 0.75, 0.75]
ref.AmbientColor = [0.75, 0.75, 0.75]
ref.LineWidth = 2.0
ColorBy(ref, None)
warp = WarpByVector(Input=reader)
warp.Vectors = ["POINTS", "displacement"]
warp.ScaleFactor = 1.0
disp = Show(warp, view)
disp.LineWidth = 5.0
ColorBy(disp, ("POINTS", "displacement", "Magnitude"))
disp.RescaleTransferFunctionToDataRange(True, False)
disp.SetScalarBarVisibility(view, True)
view.ViewTime = times[len(times) * 3 // 10]
view.CameraPosition = [0, 250, 1500]
view.CameraFocalPoint = [-100, 250, 0]
view.CameraViewUp = [0, 1, 0]
view.ResetCamera()
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=[900, 700])
print("t =", view.ViewTime)
