"""Open femcontact time series in ParaView itself (run by `make test-paraview` with pvbatch):

    pvbatch tests/paraview/check_series.py CASE_DIR FRAMES PNG

checks that fields.xdmf and rigid.xdmf of CASE_DIR each have FRAMES time steps and the arrays
femcontact writes, then renders the last frame off-screen: the deformable body warped by its
displacement (true scale) and coloured by von Mises, the rigid body warped by its own, to PNG. Exits 1 with
a message on the first check that fails."""
import sys

from paraview import simple

NODE_ARRAYS = {"displacement", "contact_pressure", "tangential_traction", "contact_status", "slip", "gap"}
CELL_ARRAYS = {"von_mises", "stress"}


def fail(message: str) -> None:
    print(f"check_series: {message}", file=sys.stderr)
    sys.exit(1)


def open_series(path: str, frames: int):
    reader = simple.Xdmf3ReaderS(FileName=[path])
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues)
    if len(times) != frames:
        fail(f"{path}: {len(times)} time steps, expected {frames}")
    reader.UpdatePipeline(times[-1])
    return reader, times


def main(case_dir: str, frames: int, png: str) -> None:
    body, times = open_series(f"{case_dir}/fields.xdmf", frames)
    data = body.GetDataInformation()
    names = ({body.PointData[k].Name for k in range(len(body.PointData))},
             {body.CellData[k].Name for k in range(len(body.CellData))})
    if names != (NODE_ARRAYS, CELL_ARRAYS):
        fail(f"fields.xdmf arrays {names}, expected {(NODE_ARRAYS, CELL_ARRAYS)}")
    rigid, rigid_times = open_series(f"{case_dir}/rigid.xdmf", frames)
    if rigid_times != times:
        fail(f"rigid.xdmf times {rigid_times} differ from fields.xdmf's {times}")
    scale = 1.0  # true scale: magnified, the rigid body's small rotation would look like a large one
    view = simple.CreateRenderView()
    view.ViewSize = [1200, 800]
    view.UseColorPaletteForBackground = 0
    view.Background = [1, 1, 1]
    view.OrientationAxesVisibility = 0
    view.ViewTime = times[-1]
    warped = simple.WarpByVector(Input=body, Vectors=["POINTS", "displacement"], ScaleFactor=scale)
    shown = simple.Show(warped, view)
    simple.ColorBy(shown, ("CELLS", "von_mises"))
    shown.RescaleTransferFunctionToDataRange(True, False)
    shown.SetScalarBarVisibility(view, True)
    bar = simple.GetScalarBar(simple.GetColorTransferFunction("von_mises"), view)
    bar.Title, bar.ComponentTitle = "von Mises (MPa)", ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    outline = simple.WarpByVector(Input=rigid, Vectors=["POINTS", "displacement"], ScaleFactor=scale)
    drawn = simple.Show(outline, view)
    drawn.ColorArrayName = [None, ""]
    drawn.AmbientColor = drawn.DiffuseColor = [0.2, 0.2, 0.2]
    drawn.LineWidth = 3.0
    plane = abs(data.GetBounds()[5] - data.GetBounds()[4]) < 1e-12
    drawn.Opacity = 1.0 if plane else 0.4  # the 3-D rigid body's surface is see-through
    if plane:
        view.InteractionMode = "2D"
        view.CameraPosition, view.CameraViewUp = [0, 0, 1], [0, 1, 0]
    else:
        view.CameraPosition, view.CameraViewUp = [1, -1.5, 1], [0, 0, 1]
    view.ResetCamera()
    simple.SaveScreenshot(png, view, ImageResolution=[1200, 800])
    print(f"check_series: {case_dir}: {len(times)} frames, t = {times[0]:g} ... {times[-1]:g} s, arrays ok; "
          f"rendered {png}")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
