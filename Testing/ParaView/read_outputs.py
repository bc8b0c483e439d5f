"""Opens VTK XML files with ParaView's own readers and checks what they read.

Usage: pvpython read_outputs.py FILE.vti|FILE.vtp|FILE.pvd ...

Each file is opened with paraview.simple.OpenDataFile (the reader ParaView's File > Open picks)
and its number of points compared with what the file's XML header promises: the WholeExtent of a
.vti, the Pieces' NumberOfPoints of a .vtp. A .pvd must list files that each read so, and its
reader must report one time step per distinct timestep and the listed files' points at each.
Anything VTK reports as an error while reading (an XML parse error above all: ParaView then
shows an empty dataset and no more than a message) fails the file. Exits 1 if any file failed.
"""
import os
import re
import sys
import xml.etree.ElementTree as ET

from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow
from paraview import servermanager
from paraview.simple import Delete, OpenDataFile


class Failure(Exception):
    pass


def xml_header(path):
    """The file's XML before any appended data, as text: raw appended bytes are no XML, and
    the expectation must not depend on the reader (or parser) under test."""
    with open(path, "rb") as f:
        data = f.read()
    cut = data.find(b"<AppendedData")
    return (data if cut < 0 else data[:cut]).decode("latin-1")


def attributes(tag_text):
    return dict(re.findall(r'([A-Za-z_][\w.-]*)="([^"]*)"', tag_text))


def header_expectation(path):
    """(VTKFile type, number of points, {"PointData"|"CellData"|"FieldData": array names})."""
    text = xml_header(path)
    root = re.search(r"<VTKFile\b([^>]*)>", text)
    if not root:
        raise Failure("no <VTKFile> element in the header")
    kind = attributes(root.group(1)).get("type", "")
    if path.endswith(".vti"):
        tag = re.search(r"<ImageData\b([^>]*)>", text)
        extent = tag and attributes(tag.group(1)).get("WholeExtent")
        if not extent:
            raise Failure("no <ImageData WholeExtent=...> in the header")
        e = [int(v) for v in extent.split()]
        points = 1
        for axis in range(3):
            points *= max(0, e[2 * axis + 1] - e[2 * axis] + 1)
    else:
        pieces = re.findall(r"<Piece\b([^>]*)>", text)
        if not pieces:
            raise Failure("no <Piece> in the header")
        points = sum(int(attributes(p).get("NumberOfPoints", "0")) for p in pieces)
    arrays = {}
    for section in ("PointData", "CellData", "FieldData"):
        names = set()
        for block in re.findall(r"<%s\b[^>]*?(?<!/)>(.*?)</%s>" % (section, section), text, re.S):
            for tag in re.findall(r"<DataArray\b([^>]*)>", block):
                name = attributes(tag).get("Name")
                if name:
                    names.add(name)
        arrays[section] = names
    return kind, points, arrays


def read_with_paraview(path, time=None, keep=None):
    """Opens PATH with ParaView's reader, updates it (at TIME), and returns the reader's output
    and what VTK printed meanwhile. KEEP(reader proxy) runs before the proxy is deleted."""
    previous = vtkOutputWindow.GetInstance()
    messages = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(messages)
    try:
        reader = OpenDataFile(path)
        if reader is None:
            raise Failure("ParaView has no reader for it")
        try:
            if time is None:
                reader.UpdatePipeline()
            else:
                reader.UpdatePipeline(time)
            output = reader.GetClientSideObject().GetOutputDataObject(0)
            copy = output.NewInstance()
            copy.ShallowCopy(output)
            extra = keep(reader) if keep else None
        finally:
            Delete(reader)
    finally:
        vtkOutputWindow.SetInstance(previous)
    return copy, messages.GetOutput(), extra


def check_messages(text):
    if "ERROR" in text or "Error parsing" in text:
        lines = [l for l in text.splitlines() if l.strip()]
        raise Failure("the reader reported errors:\n    " + "\n    ".join(lines[:6]))


def check_dataset(path):
    """Checks one .vti or .vtp; returns its number of points."""
    kind, expected, arrays = header_expectation(path)
    wanted = {".vti": "ImageData", ".vtp": "PolyData"}[os.path.splitext(path)[1]]
    if kind != wanted:
        raise Failure('VTKFile type="%s", expected "%s"' % (kind, wanted))
    data, messages, _ = read_with_paraview(path)
    check_messages(messages)
    if not data.IsA("vtk" + wanted):
        raise Failure("ParaView read a %s, expected vtk%s" % (data.GetClassName(), wanted))
    points = data.GetNumberOfPoints()
    if points != expected:
        raise Failure("ParaView read %d points, the header says %d" % (points, expected))
    held = {"PointData": data.GetPointData(), "CellData": data.GetCellData(),
            "FieldData": data.GetFieldData()}
    for section, names in arrays.items():
        missing = sorted(n for n in names if not held[section].HasArray(n))
        if missing:
            raise Failure("%s arrays missing after reading: %s" % (section, ", ".join(missing)))
    return points


def check_collection(path):
    """Checks a .pvd: its files, and the time series ParaView makes of them."""
    root = ET.parse(path).getroot()
    if root.get("type") != "Collection":
        raise Failure('VTKFile type="%s", expected "Collection"' % root.get("type"))
    entries = root.findall("./Collection/DataSet")
    if not entries:
        raise Failure("lists no <DataSet>")
    folder = os.path.dirname(path)
    per_step = {}
    for entry in entries:
        listed = os.path.join(folder, entry.get("file", ""))
        if not os.path.isfile(listed):
            raise Failure("lists %s, which does not exist" % listed)
        try:
            points = check_dataset(listed)
        except Failure as e:
            raise Failure("lists %s: %s" % (listed, e))
        step = float(entry.get("timestep", "0"))
        per_step[step] = per_step.get(step, 0) + points
    steps = sorted(per_step)
    _, messages, reported = read_with_paraview(path, keep=lambda r: list(r.TimestepValues))
    check_messages(messages)
    if len(reported) != len(steps):
        raise Failure("ParaView reports %d time steps, the file lists %d" % (len(reported), len(steps)))
    for step in steps:
        data, messages, _ = read_with_paraview(path, time=step)
        check_messages(messages)
        points = data.GetNumberOfPoints()
        if points != per_step[step]:
            raise Failure("at time %g ParaView read %d points, the listed files have %d"
                          % (step, points, per_step[step]))
    return len(entries), len(steps), sum(per_step.values())


def main(paths):
    if not paths:
        sys.stderr.write(__doc__)
        return 2
    version = servermanager.vtkSMProxyManager.GetParaViewSourceVersion()
    failed = []
    for path in paths:
        try:
            if not os.path.isfile(path):
                raise Failure("no such file")
            if path.endswith(".pvd"):
                files, steps, points = check_collection(path)
                print("ok   %s: %d files, %d time steps, %d points in all" % (path, files, steps, points))
            elif path.endswith((".vti", ".vtp")):
                print("ok   %s: %d points" % (path, check_dataset(path)))
            else:
                raise Failure("not a .vti, .vtp or .pvd")
        except (Failure, ET.ParseError, ValueError) as e:
            print("FAIL %s: %s" % (path, e))
            failed.append(path)
        sys.stdout.flush()
    if failed:
        print("read_outputs: %d of %d files do not open as they should (%s): %s"
              % (len(failed), len(paths), version, " ".join(failed)))
        return 1
    print("read_outputs: all %d files open with the expected points (%s)" % (len(paths), version))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
