// Checks files that the examples and the asrt program wrote, with VTK's readers and parsers (and
// the Ogg inspector): each exists, reads back, and holds what it should.
// Usage: asrtCheckOutputs SPEC...   where SPEC is
//   PATH.png[=WxH]  a PNG of that size with more than one colour (not a blank picture)
//   PATH.vti[=WxH]  VTK image data of that size with an RGB "Colors" array (the sum of its
//                   "RaysPerPixel", if any, is printed: "..., N rays")
//   PATH.vtp[=N]    VTK poly data with points (N of them)
//   PATH.pvd[=N]    a ParaView collection of N datasets whose files all exist
//   PATH.ogv[=N]    an Ogg Theora movie (well-formed pages) of N frames
//   !PATH           no such file (nothing left behind)
//   ~SPEC           as SPEC, but an image may be a single colour (e.g. a selection of rays)
//   A.png:B.png>=DB two PNGs of one size whose PSNR (over the three channels, 10 log10(255² /
//                   MSE)) is at least DB
#include "OggTheoraFile.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGReader.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkXMLDataElement.h"
#include "vtkXMLDataParser.h"
#include "vtkXMLImageDataReader.h"
#include "vtkXMLPolyDataReader.h"

#include <vtksys/SystemTools.hxx>

#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <string>

namespace
{
using vtksys::SystemTools;

void require(bool ok, const std::string& path, const std::string& what)
{
  if (!ok)
    throw std::runtime_error(path + ": " + what);
}

std::string size(vtkImageData* image)
{
  int dims[3];
  image->GetDimensions(dims);
  return std::to_string(dims[0]) + "x" + std::to_string(dims[1]);
}

bool allowBlank = false;

std::string checkImage(vtkImageData* image, const std::string& path, const std::string& expect,
                       const char* array)
{
  require(image && image->GetNumberOfPoints() > 0, path, "no pixels");
  require(expect.empty() || size(image) == expect, path,
          "is " + size(image) + ", expected " + expect);
  auto* colors = vtkUnsignedCharArray::SafeDownCast(array ? image->GetPointData()->GetArray(array)
                                                          : image->GetPointData()->GetScalars());
  require(colors && colors->GetNumberOfComponents() >= 3, path, "has no RGB colours");
  std::set<long> distinct;
  for (vtkIdType k = 0; k < colors->GetNumberOfTuples() && distinct.size() < 2; ++k)
    distinct.insert(colors->GetTypedComponent(k, 0) << 16 | colors->GetTypedComponent(k, 1) << 8 |
                    colors->GetTypedComponent(k, 2));
  require(allowBlank || distinct.size() >= 2, path, "is a single colour");
  return size(image);
}

vtkSmartPointer<vtkImageData> readPng(const std::string& path)
{
  vtkNew<vtkPNGReader> reader;
  require(SystemTools::FileExists(path, true), path, "missing");
  require(reader->CanReadFile(path.c_str()) != 0, path, "is not a PNG");
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkSmartPointer<vtkImageData> image = reader->GetOutput();
  return image;
}

/// PSNR of two PNGs of one size over their RGB channels; infinite for identical pictures.
std::string checkPsnr(const std::string& spec)
{
  const std::size_t ge = spec.rfind(">="), colon = spec.find(".png:");
  const std::string a = spec.substr(0, colon + 4), b = spec.substr(colon + 5, ge - colon - 5);
  const double want = std::stod(spec.substr(ge + 2));
  vtkSmartPointer<vtkImageData> ia = readPng(a), ib = readPng(b);
  require(size(ia) == size(ib), spec, "sizes differ: " + size(ia) + " and " + size(ib));
  auto* ca = vtkUnsignedCharArray::SafeDownCast(ia->GetPointData()->GetScalars());
  auto* cb = vtkUnsignedCharArray::SafeDownCast(ib->GetPointData()->GetScalars());
  require(ca && cb && ca->GetNumberOfComponents() >= 3 && cb->GetNumberOfComponents() >= 3, spec,
          "an image has no RGB colours");
  double sum = 0;
  for (vtkIdType k = 0; k < ca->GetNumberOfTuples(); ++k)
    for (int c = 0; c < 3; ++c)
    {
      const double d = double(ca->GetTypedComponent(k, c)) - double(cb->GetTypedComponent(k, c));
      sum += d * d;
    }
  const double mse = sum / (3.0 * double(ca->GetNumberOfTuples()));
  const double psnr = mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : INFINITY;
  require(psnr >= want, spec,
          "PSNR " + std::to_string(psnr) + " dB is below " + std::to_string(want));
  return "PSNR " + std::to_string(psnr) + " dB";
}

std::string check(std::string spec)
{
  if (spec.find(".png:") != std::string::npos && spec.find(">=") != std::string::npos)
    return checkPsnr(spec);
  allowBlank = !spec.empty() && spec[0] == '~';
  if (allowBlank)
    spec = spec.substr(1);
  if (!spec.empty() && spec[0] == '!')
  {
    require(!SystemTools::FileExists(spec.substr(1)), spec.substr(1), "should not exist");
    return "absent";
  }
  const std::size_t eq = spec.rfind('=');
  const std::string path = spec.substr(0, eq);
  const std::string expect = eq == std::string::npos ? "" : spec.substr(eq + 1);
  require(SystemTools::FileExists(path, true), path, "missing");
  const std::string ext = SystemTools::GetFilenameLastExtension(path);
  if (ext == ".png")
  {
    vtkNew<vtkPNGReader> reader;
    require(reader->CanReadFile(path.c_str()) != 0, path, "is not a PNG");
    reader->SetFileName(path.c_str());
    reader->Update();
    return "PNG " + checkImage(reader->GetOutput(), path, expect, nullptr);
  }
  if (ext == ".vti")
  {
    vtkNew<vtkXMLImageDataReader> reader;
    require(reader->CanReadFile(path.c_str()) != 0, path, "is not VTK XML image data");
    reader->SetFileName(path.c_str());
    reader->Update();
    std::string what = "VTI " + checkImage(reader->GetOutput(), path, expect, "Colors");
    // The rays a traced frame took (anti-aliasing's extra rays counted), for scripts that
    // compare what a run traced with tracing the frames directly.
    if (vtkDataArray* rays = reader->GetOutput()->GetPointData()->GetArray("RaysPerPixel"))
    {
      double sum = 0;
      for (vtkIdType p = 0; p < rays->GetNumberOfTuples(); ++p)
        sum += rays->GetComponent(p, 0);
      what += ", " + std::to_string(static_cast<long long>(sum)) + " rays";
    }
    return what;
  }
  if (ext == ".vtp")
  {
    vtkNew<vtkXMLPolyDataReader> reader;
    require(reader->CanReadFile(path.c_str()) != 0, path, "is not VTK XML poly data");
    reader->SetFileName(path.c_str());
    reader->Update();
    const vtkIdType n = reader->GetOutput()->GetNumberOfPoints();
    require(n > 0, path, "has no points");
    require(expect.empty() || std::to_string(n) == expect, path,
            "has " + std::to_string(n) + " points, expected " + expect);
    return "VTP " + std::to_string(n) + " points";
  }
  if (ext == ".pvd")
  {
    vtkNew<vtkXMLDataParser> parser;
    parser->SetFileName(path.c_str());
    require(parser->Parse() != 0, path, "is not XML");
    vtkXMLDataElement* root = parser->GetRootElement();
    require(root && std::string(root->GetName()) == "VTKFile" && root->GetAttribute("type") &&
              std::string(root->GetAttribute("type")) == "Collection",
            path, "is not a VTKFile of type Collection");
    vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
    require(collection != nullptr, path, "has no Collection");
    const int n = collection->GetNumberOfNestedElements();
    require(expect.empty() || std::to_string(n) == expect, path,
            "lists " + std::to_string(n) + " datasets, expected " + expect);
    const std::string dir = SystemTools::GetFilenamePath(path);
    for (int k = 0; k < n; ++k)
    {
      vtkXMLDataElement* e = collection->GetNestedElement(k);
      const char* file = e->GetAttribute("file");
      double t;
      require(std::string(e->GetName()) == "DataSet" && file &&
                e->GetScalarAttribute("timestep", t),
              path, "entry " + std::to_string(k) + " is not a DataSet with timestep and file");
      const std::string listed =
        SystemTools::FileIsFullPath(file) ? file : (dir.empty() ? "." : dir) + "/" + file;
      require(SystemTools::FileExists(listed, true), path, "lists a missing file " + listed);
    }
    return "PVD " + std::to_string(n) + " datasets";
  }
  if (ext == ".ogv")
  {
    const asrt::testing::OggTheoraInfo info = asrt::testing::inspectOggTheora(path);
    require(info.error.empty(), path, info.error);
    require(expect.empty() || std::to_string(info.frames) == expect, path,
            "has " + std::to_string(info.frames) + " frames, expected " + expect);
    return "Ogg Theora " + std::to_string(info.width) + "x" + std::to_string(info.height) + ", " +
           std::to_string(info.frames) + " frames";
  }
  throw std::runtime_error(path + ": no check for files of type '" + ext + "'");
}
}

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s SPEC...\n", argv[0]);
    return 2;
  }
  try
  {
    for (int k = 1; k < argc; ++k)
      std::printf("ok %s: %s\n", argv[k], check(argv[k]).c_str());
  }
  catch (const std::exception& e)
  {
    std::printf("FAILED %s\n", e.what());
    return 1;
  }
  return 0;
}
