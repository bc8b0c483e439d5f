// The VTK XML files of Apps/Tools/DataFiles with every compression: byte for byte what VTK's own
// writers make of the same data one block after another, the same bytes at any number of
// threads, and read back by VTK's readers equal to the data written.
#include "DataFiles.h"

#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"
#include "vtkXMLImageDataReader.h"
#include "vtkXMLImageDataWriter.h"
#include "vtkXMLPolyDataReader.h"
#include "vtkXMLPolyDataWriter.h"

#include <vtksys/SystemTools.hxx>

#include <gtest/gtest.h>

#include <omp.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

using namespace asrt::tools;
using vtksys::SystemTools;

namespace
{
const XmlCompression kAll[] = { XmlCompression::LZ4, XmlCompression::ZLib,
                                XmlCompression::ZLibFastest, XmlCompression::None };

std::string nameOf(XmlCompression c)
{
  switch (c)
  {
    case XmlCompression::LZ4:
      return "lz4";
    case XmlCompression::ZLib:
      return "zlib";
    case XmlCompression::ZLibFastest:
      return "zlib1";
    case XmlCompression::None:
      return "none";
  }
  return "?";
}

std::string scratch(const std::string& name)
{
  const std::string dir = std::string(ASRT_TEST_OUTPUT_DIR) + "/" + name;
  SystemTools::RemoveADirectory(dir);
  SystemTools::MakeDirectory(dir);
  return dir;
}

std::string contentOf(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Numbers that compress as a frame's do, partly: smooth runs with noise in the low bits, and
/// repeated values (a reproducible sequence, no library random generator).
double sample(std::uint64_t& state, vtkIdType k)
{
  state = state * 6364136223846793005ULL + 1442695040888963407ULL;
  const double noise = static_cast<double>(state >> 11) * 0x1.0p-53;
  return (k % 7 == 0) ? 1.0 : 0.001 * static_cast<double>(k) + 1e-6 * noise;
}

/// An image whose arrays span many compression blocks (the largest over 256 blocks of 32 KiB, so
/// over one batch), of four number types, with a string in its field data.
vtkSmartPointer<vtkImageData> image(int width, int height)
{
  auto frame = vtkSmartPointer<vtkImageData>::New();
  frame->SetDimensions(width, height, 1);
  const vtkIdType n = static_cast<vtkIdType>(width) * height;
  std::uint64_t state = 1;
  vtkNew<vtkUnsignedCharArray> colors;
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> surface;
  surface->SetName("Surface");
  surface->SetNumberOfComponents(3);
  surface->SetNumberOfTuples(n);
  vtkNew<vtkIntArray> object;
  object->SetName("ObjectId");
  object->SetNumberOfTuples(n);
  vtkNew<vtkFloatArray> length;
  length->SetName("PathLength");
  length->SetNumberOfTuples(n);
  for (vtkIdType k = 0; k < n; ++k)
  {
    for (int c = 0; c < 3; ++c)
    {
      colors->SetTypedComponent(k, c, static_cast<unsigned char>((k * (c + 3)) % 251));
      surface->SetTypedComponent(k, c, sample(state, k) * (c + 1));
    }
    object->SetValue(k, static_cast<int>(k / 1000 % 5) - 1);
    length->SetValue(k, static_cast<float>(sample(state, k)));
  }
  frame->GetPointData()->AddArray(colors);
  frame->GetPointData()->AddArray(surface);
  frame->GetPointData()->AddArray(object);
  frame->GetPointData()->AddArray(length);
  vtkNew<vtkStringArray> method;
  method->SetName("IntegrationMethod");
  method->InsertNextValue("PlanarOrbit");
  frame->GetFieldData()->AddArray(method);
  return frame;
}

/// The image's pixels as points (doubles), one vertex each, with its point data.
vtkSmartPointer<vtkPolyData> points(vtkImageData* frame)
{
  auto hits = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> xyz;
  xyz->SetDataTypeToDouble();
  const vtkIdType n = frame->GetNumberOfPoints();
  xyz->SetNumberOfPoints(n);
  vtkDataArray* surface = frame->GetPointData()->GetArray("Surface");
  vtkNew<vtkCellArray> vertices;
  for (vtkIdType k = 0; k < n; ++k)
  {
    xyz->SetPoint(k, surface->GetTuple3(k));
    vertices->InsertNextCell(1, &k);
  }
  hits->SetPoints(xyz);
  hits->SetVerts(vertices);
  hits->GetPointData()->ShallowCopy(frame->GetPointData());
  hits->GetFieldData()->ShallowCopy(frame->GetFieldData());
  return hits;
}

/// VTK's own writer, on its own file, with the compression `c` stands for.
void writeSerially(vtkXMLWriter* writer, vtkDataObject* data, XmlCompression c,
                   const std::string& path)
{
  writer->SetInputData(data);
  writer->SetDataModeToBinary();
  if (c == XmlCompression::LZ4)
    writer->SetCompressorTypeToLZ4();
  else if (c == XmlCompression::None)
    writer->SetCompressorTypeToNone();
  else
  {
    writer->SetCompressorTypeToZLib();
    if (c == XmlCompression::ZLibFastest)
      writer->SetCompressionLevel(1);
  }
  writer->SetFileName(path.c_str());
  ASSERT_EQ(writer->Write(), 1) << path;
  // As DataFiles leaves them: no cached ranges that a later write would add to the file.
  vtkFieldData* const groups[] = { data->GetFieldData(),
                                   vtkDataSet::SafeDownCast(data)->GetPointData() };
  for (vtkFieldData* fd : groups)
    for (int k = 0; k < fd->GetNumberOfArrays(); ++k)
      fd->GetAbstractArray(k)->GetInformation()->Clear();
  if (auto* set = vtkPointSet::SafeDownCast(data))
    set->GetPoints()->GetData()->GetInformation()->Clear();
}

void expectSameArrays(vtkFieldData* read, vtkFieldData* written, const std::string& what)
{
  ASSERT_EQ(read->GetNumberOfArrays(), written->GetNumberOfArrays()) << what;
  for (int a = 0; a < written->GetNumberOfArrays(); ++a)
  {
    vtkAbstractArray* w = written->GetAbstractArray(a);
    vtkAbstractArray* r = read->GetAbstractArray(w->GetName());
    ASSERT_NE(r, nullptr) << what << ": no array " << w->GetName();
    ASSERT_EQ(r->GetDataType(), w->GetDataType()) << what << ": " << w->GetName();
    ASSERT_EQ(r->GetNumberOfValues(), w->GetNumberOfValues()) << what << ": " << w->GetName();
    if (auto* ws = vtkStringArray::SafeDownCast(w))
    {
      for (vtkIdType k = 0; k < ws->GetNumberOfValues(); ++k)
        EXPECT_EQ(vtkStringArray::SafeDownCast(r)->GetValue(k), ws->GetValue(k));
      continue;
    }
    auto* wd = vtkDataArray::SafeDownCast(w);
    auto* rd = vtkDataArray::SafeDownCast(r);
    ASSERT_EQ(rd->GetNumberOfComponents(), wd->GetNumberOfComponents()) << w->GetName();
    for (vtkIdType k = 0; k < wd->GetNumberOfTuples(); ++k)
      for (int c = 0; c < wd->GetNumberOfComponents(); ++c)
        ASSERT_EQ(rd->GetComponent(k, c), wd->GetComponent(k, c))
          << what << ": " << w->GetName() << " tuple " << k << " component " << c;
  }
}
}

TEST(XmlCompression, FilesAreWhatVtksWritersMakeOneBlockAfterAnother)
{
  const std::string dir = scratch("xml-serial");
  vtkSmartPointer<vtkImageData> frame = image(800, 600);
  vtkSmartPointer<vtkPolyData> hits = points(frame);
  for (XmlCompression c : kAll)
  {
    const std::string name = dir + "/" + nameOf(c);
    writeVti(frame, name + ".vti", c);
    writeVtp(hits, name + ".vtp", c);
    vtkNew<vtkXMLImageDataWriter> vti;
    writeSerially(vti, frame, c, name + "-vtk.vti");
    vtkNew<vtkXMLPolyDataWriter> vtp;
    writeSerially(vtp, hits, c, name + "-vtk.vtp");
    const std::string ours = contentOf(name + ".vti");
    EXPECT_GT(ours.size(), 1000u);
    EXPECT_TRUE(ours == contentOf(name + "-vtk.vti")) << nameOf(c) << ": the .vti differs";
    EXPECT_TRUE(contentOf(name + ".vtp") == contentOf(name + "-vtk.vtp"))
      << nameOf(c) << ": the .vtp differs";
  }
}

TEST(XmlCompression, TheSameBytesAtAnyThreadCount)
{
  const std::string dir = scratch("xml-threads");
  vtkSmartPointer<vtkImageData> frame = image(800, 600);
  vtkSmartPointer<vtkPolyData> hits = points(frame);
  const int threads = omp_get_max_threads();
  for (XmlCompression c : kAll)
  {
    std::string first[2];
    for (int t : { 1, 2, 3 })
    {
      omp_set_num_threads(t);
      const std::string name = dir + "/" + nameOf(c) + "-" + std::to_string(t);
      writeVti(frame, name + ".vti", c);
      writeVtp(hits, name + ".vtp", c);
      const std::string files[2] = { contentOf(name + ".vti"), contentOf(name + ".vtp") };
      if (t == 1)
      {
        first[0] = files[0];
        first[1] = files[1];
        continue;
      }
      EXPECT_TRUE(files[0] == first[0]) << nameOf(c) << ": the .vti differs on " << t << " threads";
      EXPECT_TRUE(files[1] == first[1]) << nameOf(c) << ": the .vtp differs on " << t << " threads";
    }
  }
  omp_set_num_threads(threads);
}

TEST(XmlCompression, FilesReadBackEqualToTheData)
{
  const std::string dir = scratch("xml-read");
  // Not a whole number of blocks, and not a multiple of 3 bytes in any array.
  vtkSmartPointer<vtkImageData> frame = image(801, 599);
  vtkSmartPointer<vtkPolyData> hits = points(frame);
  for (XmlCompression c : kAll)
  {
    const std::string name = dir + "/" + nameOf(c);
    writeVti(frame, name + ".vti", c);
    writeVtp(hits, name + ".vtp", c);
    vtkNew<vtkXMLImageDataReader> vti;
    vti->SetFileName((name + ".vti").c_str());
    vti->Update();
    int dims[3];
    vti->GetOutput()->GetDimensions(dims);
    EXPECT_EQ(dims[0], 801);
    EXPECT_EQ(dims[1], 599);
    expectSameArrays(vti->GetOutput()->GetPointData(), frame->GetPointData(),
                     nameOf(c) + ".vti point data");
    expectSameArrays(vti->GetOutput()->GetFieldData(), frame->GetFieldData(),
                     nameOf(c) + ".vti field data");

    vtkNew<vtkXMLPolyDataReader> vtp;
    vtp->SetFileName((name + ".vtp").c_str());
    vtp->Update();
    vtkPolyData* read = vtp->GetOutput();
    ASSERT_EQ(read->GetNumberOfPoints(), hits->GetNumberOfPoints()) << nameOf(c);
    ASSERT_EQ(read->GetNumberOfVerts(), hits->GetNumberOfPoints()) << nameOf(c);
    ASSERT_EQ(read->GetPoints()->GetDataType(), VTK_DOUBLE) << nameOf(c);
    for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
    {
      double p[3], q[3];
      read->GetPoint(k, p);
      hits->GetPoint(k, q);
      ASSERT_TRUE(p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) << nameOf(c) << " point " << k;
    }
    expectSameArrays(read->GetPointData(), hits->GetPointData(), nameOf(c) + ".vtp point data");
    expectSameArrays(read->GetFieldData(), hits->GetFieldData(), nameOf(c) + ".vtp field data");
  }
}
