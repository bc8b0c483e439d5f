// The helpers behind the asrt program and the examples (Apps/Tools): .pvd collections read back by
// VTK's XML parser, images and datasets read back by VTK's readers, movies checked against the
// Ogg and Theora specifications, VTK error messages, the camera orbit, ray fans, the deflection
// measurement against Darwin's formula, and the progress display.
#include "AtomicFile.h"
#include "CameraOrbit.h"
#include "DataFiles.h"
#include "Measurements.h"
#include "MovieWriter.h"
#include "OggTheoraFile.h"
#include "Progress.h"
#include "PvdCollection.h"
#include "RayBundleView.h"
#include "VtkMessages.h"
#include "vtkGeodesicSource.h"

#include "vtkDirectory.h"
#include "vtkDoubleArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPNGReader.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkXMLDataElement.h"
#include "vtkXMLDataParser.h"
#include "vtkXMLImageDataReader.h"
#include "vtkXMLPolyDataReader.h"

#include <vtksys/SystemTools.hxx>

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

using namespace asrt::tools;
using vtksys::SystemTools;

namespace
{
/// A fresh, empty directory for one test.
std::string scratch(const std::string& name)
{
  const std::string dir = std::string(ASRT_TEST_OUTPUT_DIR) + "/" + name;
  SystemTools::RemoveADirectory(dir);
  SystemTools::MakeDirectory(dir);
  return dir;
}

std::vector<std::string> filesIn(const std::string& dir)
{
  vtkNew<vtkDirectory> d;
  std::vector<std::string> names;
  if (d->Open(dir.c_str()))
    for (vtkIdType k = 0; k < d->GetNumberOfFiles(); ++k)
      if (std::string(d->GetFile(k)) != "." && std::string(d->GetFile(k)) != "..")
        names.emplace_back(d->GetFile(k));
  return names;
}

/// A width × height RGB image whose pixel (i, j) is (i, j, i + j) scaled, so that every pixel
/// differs and a flipped or shifted copy is detected.
vtkSmartPointer<vtkImageData> gradient(int width, int height, int shift = 0)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(width, height, 1);
  vtkNew<vtkUnsignedCharArray> colors;
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(static_cast<vtkIdType>(width) * height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
    {
      const unsigned char rgb[3] = { static_cast<unsigned char>((7 * i + shift) % 256),
                                     static_cast<unsigned char>((11 * j) % 256),
                                     static_cast<unsigned char>((3 * i + 5 * j) % 256) };
      colors->SetTypedTuple(static_cast<vtkIdType>(j) * width + i, rgb);
    }
  image->GetPointData()->AddArray(colors);
  vtkNew<vtkDoubleArray> values;
  values->SetName("Values");
  values->SetNumberOfTuples(static_cast<vtkIdType>(width) * height);
  for (vtkIdType k = 0; k < values->GetNumberOfTuples(); ++k)
    values->SetValue(k, 0.1 * k);
  image->GetPointData()->AddArray(values);
  return image;
}

std::string scenePath(const char* name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/scenes/" + name;
}
}

// ---------------------------------------------------------------------------------------------
// .pvd collections

TEST(PvdCollection, VtkXmlParserReadsTheSeriesBack)
{
  const std::string dir = scratch("pvd");
  PvdCollection pvd;
  // Time steps that only a round-tripping format keeps exactly.
  const double steps[] = { 0.1, 2.0 / 3.0, 1e-300 };
  pvd.add(steps[0], dir + "/frame-000.vti");
  pvd.add(steps[1], dir + "/sub/frame & \"001\".vti", 1);
  pvd.add(steps[2], "/elsewhere/frame-002.vti");
  pvd.write(dir + "/series.pvd");

  vtkNew<vtkXMLDataParser> parser;
  parser->SetFileName((dir + "/series.pvd").c_str());
  ASSERT_TRUE(parser->Parse());
  vtkXMLDataElement* root = parser->GetRootElement();
  EXPECT_STREQ(root->GetName(), "VTKFile");
  EXPECT_STREQ(root->GetAttribute("type"), "Collection");
  vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
  ASSERT_NE(collection, nullptr);
  ASSERT_EQ(collection->GetNumberOfNestedElements(), 3);
  const char* files[] = { "frame-000.vti", "sub/frame & \"001\".vti", "/elsewhere/frame-002.vti" };
  for (int k = 0; k < 3; ++k)
  {
    vtkXMLDataElement* e = collection->GetNestedElement(k);
    EXPECT_STREQ(e->GetName(), "DataSet");
    double t = -1;
    ASSERT_TRUE(e->GetScalarAttribute("timestep", t));
    EXPECT_EQ(t, steps[k]) << "time step " << k << " did not round-trip";
    EXPECT_STREQ(e->GetAttribute("file"), files[k]) << "files inside the .pvd's folder are "
                                                       "relative, others keep their path";
  }
  int part = -1;
  collection->GetNestedElement(1)->GetScalarAttribute("part", part);
  EXPECT_EQ(part, 1);
  EXPECT_EQ(filesIn(dir).size(), 1u) << "a temporary file was left next to the .pvd";
}

TEST(PvdCollection, UnwritablePlaceThrowsAndLeavesNothing)
{
  const std::string dir = scratch("pvd-unwritable");
  PvdCollection pvd;
  pvd.add(0, dir + "/a.vti");
  EXPECT_THROW(pvd.write(dir + "/missing/series.pvd"), std::runtime_error);
  EXPECT_TRUE(filesIn(dir).empty());
}

// ---------------------------------------------------------------------------------------------
// Images and datasets

TEST(DataFiles, PngReadsBackPixelForPixel)
{
  const std::string dir = scratch("png");
  vtkSmartPointer<vtkImageData> image = gradient(7, 5);
  image->GetPointData()->SetActiveScalars("Values"); // not the colours: writePng picks "Colors"
  writePng(image, dir + "/g.png");
  EXPECT_STREQ(image->GetPointData()->GetScalars()->GetName(), "Values")
    << "writing changed the caller's active scalars";
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName((dir + "/g.png").c_str());
  reader->Update();
  int dims[3];
  reader->GetOutput()->GetDimensions(dims);
  ASSERT_EQ(dims[0], 7);
  ASSERT_EQ(dims[1], 5);
  vtkDataArray* read = reader->GetOutput()->GetPointData()->GetScalars();
  vtkDataArray* written = image->GetPointData()->GetArray("Colors");
  for (vtkIdType k = 0; k < 35; ++k)
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(read->GetComponent(k, c), written->GetComponent(k, c)) << "pixel " << k;
}

TEST(DataFiles, VtiAndVtpKeepEveryArray)
{
  const std::string dir = scratch("xml");
  vtkSmartPointer<vtkImageData> image = gradient(6, 4);
  writeVti(image, dir + "/g.vti");
  vtkNew<vtkXMLImageDataReader> vti;
  vti->SetFileName((dir + "/g.vti").c_str());
  vti->Update();
  vtkDataArray* values = vti->GetOutput()->GetPointData()->GetArray("Values");
  ASSERT_NE(values, nullptr);
  for (vtkIdType k = 0; k < 24; ++k)
    EXPECT_EQ(values->GetTuple1(k), 0.1 * k);
  ASSERT_NE(vti->GetOutput()->GetPointData()->GetArray("Colors"), nullptr);

  vtkNew<vtkPolyData> points;
  vtkNew<vtkPoints> xyz;
  xyz->SetDataTypeToDouble(); // as the source's: doubles must survive the file
  xyz->InsertNextPoint(1, 2, 3);
  xyz->InsertNextPoint(-4, 5.5, 1e-17);
  points->SetPoints(xyz);
  writeVtp(points, dir + "/p.vtp");
  vtkNew<vtkXMLPolyDataReader> vtp;
  vtp->SetFileName((dir + "/p.vtp").c_str());
  vtp->Update();
  ASSERT_EQ(vtp->GetOutput()->GetNumberOfPoints(), 2);
  double p[3];
  vtp->GetOutput()->GetPoint(1, p);
  EXPECT_EQ(p[2], 1e-17);
}

TEST(DataFiles, FailuresThrowNameTheFileAndLeaveNothing)
{
  const std::string dir = scratch("png-fail");
  try
  {
    writePng(gradient(4, 4), dir + "/missing/g.png");
    FAIL() << "no error for a missing directory";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("missing/g.png"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("ERROR: In"), std::string::npos) << e.what();
  }
  vtkNew<vtkImageData> grey;
  grey->SetDimensions(2, 2, 1);
  grey->AllocateScalars(VTK_DOUBLE, 1);
  EXPECT_THROW(writePng(grey, dir + "/grey.png"), std::runtime_error);
  EXPECT_THROW(writeVti(nullptr, dir + "/none.vti"), std::runtime_error);
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(DataFiles, SideBySideWritesAreTheFilesWrittenAlone)
{
  // One image's PNG and VTI encoded at once read the same arrays: each file must come out byte
  // for byte as written alone, and a failed write must throw after the others ended, the set then
  // leaving nothing behind.
  const std::string dir = scratch("side");
  vtkSmartPointer<vtkImageData> image = gradient(320, 200);
  writePng(image, dir + "/alone.png");
  writeVti(image, dir + "/alone.vti");
  {
    AtomicFileSet files;
    TemporaryFile& png = files.add(dir + "/both.png");
    TemporaryFile& vti = files.add(dir + "/both.vti");
    writeSideBySide({ [&] { writePng(image, png); }, [&] { writeVti(image, vti); } });
    files.commit();
  }
  auto bytes = [](const std::string& path)
  {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(dir + "/both.png"), bytes(dir + "/alone.png"));
  EXPECT_EQ(bytes(dir + "/both.vti"), bytes(dir + "/alone.vti"));
  // Encoded in memory: the bytes of the files (a movie stores them with the frame).
  EXPECT_TRUE(encodePng(image) == bytes(dir + "/alone.png"));
  const std::string vti = encodeVti(image);
  EXPECT_GT(vti.size(), 1000u);
  EXPECT_TRUE(vti == bytes(dir + "/alone.vti"));
  EXPECT_THROW(encodeVti(nullptr), std::runtime_error);

  const std::string failing = scratch("side-fail");
  vtkNew<vtkImageData> grey; // no colours: its PNG cannot be written
  grey->SetDimensions(2, 2, 1);
  grey->AllocateScalars(VTK_DOUBLE, 1);
  bool vtiWritten = false;
  {
    AtomicFileSet files;
    TemporaryFile& png = files.add(failing + "/grey.png");
    TemporaryFile& vti = files.add(failing + "/image.vti");
    EXPECT_THROW(writeSideBySide({ [&] { writePng(grey, png); },
                                   [&]
                                   {
                                     writeVti(image, vti);
                                     vtiWritten = true;
                                   } }),
                 std::runtime_error);
  }
  EXPECT_TRUE(vtiWritten) << "the other write must run to its end";
  EXPECT_TRUE(filesIn(failing).empty());
}

TEST(AtomicFile, AFailedWriteKeepsTheOldFileAndLeavesNoTemporary)
{
  const std::string dir = scratch("atomic");
  writeFileAtomically(dir + "/f.txt", "old");
  EXPECT_THROW(writeAtomically(dir + "/f.txt",
                               [](const std::string& tmp)
                               {
                                 std::ofstream(tmp) << "half";
                                 throw std::runtime_error("interrupted");
                               }),
               std::runtime_error);
  std::ifstream in(dir + "/f.txt");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "old");
  EXPECT_EQ(filesIn(dir).size(), 1u);
}

namespace
{
std::string contentOf(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeText(const std::string& path, const std::string& text)
{
  std::ofstream(path, std::ios::binary) << text;
}

bool isSymlink(const std::string& path)
{
  struct stat st;
  return lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode);
}

/// A process id that was in use and is no longer: a child that has exited and been reaped.
pid_t deadPid()
{
  const pid_t child = fork();
  if (child == 0)
    _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}
}

TEST(DataFiles, AFileDoesNotDependOnWhatWasWrittenBeforeFromItsArrays)
{
  // A frame's image and hit points share arrays (vtkGeodesicSource); VTK's writers cache ranges
  // in an array's information, and write an array with information keys in another form.
  const std::string dir = scratch("xml-shared");
  vtkSmartPointer<vtkImageData> image = gradient(6, 4);
  vtkDataArray* values = image->GetPointData()->GetArray("Values");
  vtkNew<vtkDoubleArray> labelled;
  labelled->SetName("Labelled");
  labelled->SetNumberOfTuples(24);
  labelled->Fill(2.5);
  labelled->GetInformation()->Set(vtkDataArray::UNITS_LABEL(), "m");
  vtkNew<vtkPolyData> points;
  vtkNew<vtkPoints> xyz;
  xyz->SetDataTypeToDouble();
  for (int k = 0; k < 24; ++k)
    xyz->InsertNextPoint(k, 0.5 * k, -k);
  points->SetPoints(xyz);
  points->GetPointData()->AddArray(values);
  points->GetPointData()->AddArray(labelled);
  image->GetPointData()->AddArray(labelled);

  writeVtp(points, dir + "/first.vtp");
  const std::string alone = contentOf(dir + "/first.vtp");
  EXPECT_NE(alone.find("Name=\"Values\""), std::string::npos);
  EXPECT_EQ(values->GetInformation()->GetNumberOfKeys(), 0) << "writing left keys behind";
  writeVti(image, dir + "/g.vti");
  writeVtp(points, dir + "/second.vtp");
  EXPECT_EQ(contentOf(dir + "/second.vtp"), alone)
    << "the .vtp differs once the .vti was written from an array it shares";
  // The caller's own information stays.
  EXPECT_TRUE(labelled->GetInformation()->Has(vtkDataArray::UNITS_LABEL()));
  EXPECT_STREQ(labelled->GetInformation()->Get(vtkDataArray::UNITS_LABEL()), "m");
}

TEST(AtomicFile, TemporariesAreNewHiddenFilesNamedWithThePid)
{
  const std::string dir = scratch("atomic-names");
  AtomicFileSet files;
  TemporaryFile& file = files.add(dir + "/f.txt");
  const std::string name = SystemTools::GetFilenameName(file.temporaryPath());
  pid_t writer = 0;
  EXPECT_TRUE(isTemporaryName(name, &writer)) << name;
  EXPECT_EQ(writer, getpid());
  EXPECT_EQ(name.rfind(".f.txt." + std::to_string(getpid()) + ".", 0), 0u) << name;
  struct stat st;
  ASSERT_EQ(lstat(file.temporaryPath().c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(st.st_mode & 0022, 0u) << "group or others may write the new file";
  // Two temporaries of one name differ: the name cannot be guessed from the pid alone.
  AtomicFileSet others;
  EXPECT_NE(others.add(dir + "/f.txt").temporaryPath(), file.temporaryPath());
  EXPECT_FALSE(isTemporaryName("f.txt"));
  EXPECT_FALSE(isTemporaryName(".f.txt.123.part")); // no random part
  EXPECT_FALSE(isTemporaryName(".f.txt.12a.abcdef.part"));
}

TEST(AtomicFile, ALinkPlantedAtTheOldTemporaryNameIsNotWrittenThrough)
{
  const std::string dir = scratch("atomic-planted-temp");
  const std::string victim = scratch("atomic-victim") + "/victim";
  writeText(victim, "precious");
  // The name the program used to write to: ".NAME.PID.part".
  const std::string predictable = dir + "/.f.txt." + std::to_string(getpid()) + ".part";
  ASSERT_EQ(symlink(victim.c_str(), predictable.c_str()), 0);
  writeFileAtomically(dir + "/f.txt", "new");
  EXPECT_EQ(contentOf(victim), "precious");
  EXPECT_EQ(contentOf(dir + "/f.txt"), "new");
  EXPECT_TRUE(isSymlink(predictable)) << "someone else's link was touched";
}

TEST(AtomicFile, ALinkAtTheFinalNameIsReplacedNotFollowed)
{
  const std::string dir = scratch("atomic-planted-final");
  const std::string victim = scratch("atomic-victim-final") + "/victim";
  writeText(victim, "precious");
  ASSERT_EQ(symlink(victim.c_str(), (dir + "/f.txt").c_str()), 0);
  writeFileAtomically(dir + "/f.txt", "new");
  EXPECT_EQ(contentOf(victim), "precious");
  EXPECT_FALSE(isSymlink(dir + "/f.txt"));
  EXPECT_EQ(contentOf(dir + "/f.txt"), "new");
}

TEST(AtomicFile, TheTemporaryIsCreatedExclusively)
{
  // A writer handed the temporary's file name by a VTK writer reopens the file created, not the
  // name: replacing the name by a link after creation changes nothing written.
  const std::string dir = scratch("atomic-excl");
  const std::string victim = scratch("atomic-victim-excl") + "/victim";
  writeText(victim, "precious");
  AtomicFileSet files;
  TemporaryFile& file = files.add(dir + "/f.txt");
  ASSERT_EQ(std::remove(file.temporaryPath().c_str()), 0);
  ASSERT_EQ(symlink(victim.c_str(), file.temporaryPath().c_str()), 0);
  std::ofstream(file.openName(), std::ios::binary) << "new";
  EXPECT_EQ(contentOf(victim), "precious");
  EXPECT_THROW(files.commit(), std::runtime_error) << "a replaced temporary was put in place";
  EXPECT_EQ(contentOf(victim), "precious");
  EXPECT_FALSE(SystemTools::FileExists(dir + "/f.txt"));
}

TEST(AtomicFile, ASetAppearsTogetherOrNotAtAll)
{
  const std::string dir = scratch("atomic-set");
  writeText(dir + "/a", "old a");
  writeText(dir + "/b", "old b");
  {
    AtomicFileSet files;
    files.add(dir + "/a").write("new a", 5);
    files.add(dir + "/b").write("new b", 5);
    files.add(dir + "/c").write("new c", 5);
    EXPECT_EQ(contentOf(dir + "/a"), "old a") << "a member appeared before the commit";
    // Destroyed without commit: an error or an interrupt before the last step.
  }
  EXPECT_EQ(contentOf(dir + "/a"), "old a");
  EXPECT_EQ(contentOf(dir + "/b"), "old b");
  EXPECT_EQ(filesIn(dir).size(), 2u) << "a temporary or a new file was left";

  AtomicFileSet files;
  files.add(dir + "/a").write("new a", 5);
  files.add(dir + "/c").write("new c", 5);
  files.commit();
  EXPECT_EQ(contentOf(dir + "/a"), "new a");
  EXPECT_EQ(contentOf(dir + "/b"), "old b");
  EXPECT_EQ(contentOf(dir + "/c"), "new c");
  EXPECT_EQ(filesIn(dir).size(), 3u);
}

TEST(AtomicFile, AFailedRenameUndoesTheMembersAlreadyInPlace)
{
  const std::string dir = scratch("atomic-undo");
  writeText(dir + "/a", "old a");
  writeText(dir + "/b", "old b");
  AtomicFileSet files;
  files.add(dir + "/a").write("new a", 5);
  files.add(dir + "/b").write("new b", 5);
  files.add(dir + "/c").write("new c", 5);
  // c becomes a directory that is not empty after its temporary was made: its rename fails
  // after a and b were renamed.
  ASSERT_TRUE(SystemTools::MakeDirectory(dir + "/c/inside"));
  EXPECT_THROW(files.commit(), std::runtime_error);
  EXPECT_EQ(contentOf(dir + "/a"), "old a");
  EXPECT_EQ(contentOf(dir + "/b"), "old b");
  EXPECT_TRUE(SystemTools::FileIsDirectory(dir + "/c"));
  EXPECT_EQ(filesIn(dir).size(), 3u) << "a temporary or a backup was left";
}

TEST(AtomicFile, ADirectoryAtTheNameIsRefusedBeforeAnythingIsWritten)
{
  const std::string dir = scratch("atomic-dir");
  ASSERT_TRUE(SystemTools::MakeDirectory(dir + "/f.txt"));
  AtomicFileSet files;
  EXPECT_THROW(files.add(dir + "/f.txt"), std::runtime_error);
  EXPECT_THROW(files.add(dir + "/missing/f.txt"), std::runtime_error);
  files.add(dir + "/g.txt");
  EXPECT_THROW(files.add(dir + "/g.txt"), std::runtime_error) << "one name twice in a set";
}

TEST(AtomicFile, StaleTemporariesOfDeadWritersAreRemovedOthersKept)
{
  const std::string dir = scratch("atomic-stale");
  const std::string dead = dir + "/.f.txt." + std::to_string(deadPid()) + ".AbC123.part";
  // Process 1 is always alive; this process's own temporaries may be in use.
  const std::string live = dir + "/.f.txt.1.AbC123.part";
  const std::string mine = dir + "/.f.txt." + std::to_string(getpid()) + ".AbC123.part";
  const std::string notOurs = dir + "/.f.txt.part";
  for (const std::string& path : { dead, live, mine, notOurs })
    writeText(path, "x");
  EXPECT_EQ(removeStaleTemporaries(dir), 1);
  EXPECT_FALSE(SystemTools::FileExists(dead));
  EXPECT_TRUE(SystemTools::FileExists(live));
  EXPECT_TRUE(SystemTools::FileExists(mine));
  EXPECT_TRUE(SystemTools::FileExists(notOurs));

  // Writing into a directory cleans it (once).
  const std::string dir2 = scratch("atomic-stale-write");
  const std::string dead2 = dir2 + "/.g.png." + std::to_string(deadPid()) + ".xYz789.part";
  writeText(dead2, "x");
  writeFileAtomically(dir2 + "/f.txt", "new");
  EXPECT_FALSE(SystemTools::FileExists(dead2));
}

// ---------------------------------------------------------------------------------------------
// Movies

TEST(MovieWriter, OggTheoraHasEveryFrameAtTheRightSizeAndRate)
{
  const std::string dir = scratch("ogv");
  {
    MovieWriter movie(dir + "/m.ogv", 5);
    for (int k = 0; k < 6; ++k)
      movie.addFrame(gradient(50, 30, 10 * k)); // odd sizes: Theora pads to 16, keeps the picture
    EXPECT_EQ(movie.frameCount(), 6);
    EXPECT_TRUE(filesIn(dir).size() <= 1u);
    movie.close();
  }
  const asrt::testing::OggTheoraInfo info = asrt::testing::inspectOggTheora(dir + "/m.ogv");
  ASSERT_EQ(info.error, "");
  EXPECT_EQ(info.width, 50);
  EXPECT_EQ(info.height, 30);
  EXPECT_EQ(info.rateNum, 5u * info.rateDen);
  EXPECT_EQ(info.frames, 6);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{ "m.ogv" });
}

TEST(MovieWriter, TheSameFramesMakeTheSameBytesWhateverTheClock)
{
  // VTK's Ogg writer seeds the stream's serial number with the clock's second: the second movie
  // is written in a later second than the first.
  const std::string dir = scratch("ogv-again");
  auto write = [&dir](const std::string& name)
  {
    MovieWriter movie(dir + "/" + name, 5);
    for (int k = 0; k < 4; ++k)
      movie.addFrame(gradient(40, 24, 20 * k));
    movie.close();
  };
  const std::time_t first = std::time(nullptr);
  write("a.ogv");
  while (std::time(nullptr) == first)
    usleep(20000);
  write("b.ogv");
  ASSERT_FALSE(contentOf(dir + "/a.ogv").empty());
  EXPECT_TRUE(contentOf(dir + "/a.ogv") == contentOf(dir + "/b.ogv"));
  // Still a movie its readers take: every page's checksum holds, every frame is there.
  const asrt::testing::OggTheoraInfo info = asrt::testing::inspectOggTheora(dir + "/b.ogv");
  ASSERT_EQ(info.error, "");
  EXPECT_EQ(info.frames, 4);
  EXPECT_EQ(info.width, 40);
}

TEST(MovieWriter, TheInspectorRejectsACorruptedMovie)
{
  // The check above could pass vacuously if the inspector accepted anything.
  const std::string dir = scratch("ogv-corrupt");
  {
    MovieWriter movie(dir + "/m.ogv", 5);
    for (int k = 0; k < 3; ++k)
      movie.addFrame(gradient(32, 32, k));
    movie.close();
  }
  std::fstream f(dir + "/m.ogv", std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(200);
  f.put('\x5a');
  f.close();
  EXPECT_NE(asrt::testing::inspectOggTheora(dir + "/m.ogv").error, "");
}

TEST(MovieWriter, BadUseThrowsAndLeavesNothing)
{
  const std::string dir = scratch("ogv-bad");
  EXPECT_THROW(MovieWriter(dir + "/m.avi"), std::invalid_argument);
  EXPECT_THROW(MovieWriter(dir + "/m.ogv", 0), std::invalid_argument);
  {
    MovieWriter movie(dir + "/m.ogv");
    movie.addFrame(gradient(16, 16));
    EXPECT_THROW(movie.addFrame(gradient(18, 16)), std::runtime_error);
    vtkNew<vtkImageData> grey;
    grey->SetDimensions(16, 16, 1);
    grey->AllocateScalars(VTK_FLOAT, 1);
    EXPECT_THROW(movie.addFrame(grey), std::runtime_error);
    // Destroyed without close(): abandoned.
  }
  {
    MovieWriter empty(dir + "/empty.ogv");
    EXPECT_THROW(empty.close(), std::runtime_error);
  }
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(MovieWriter, Mp4ThroughFfmpeg)
{
  if (!MovieWriter::mp4Available())
    GTEST_SKIP() << "ffmpeg is not installed: MP4 unavailable (Ogg Theora is always there)";
  const std::string dir = scratch("mp4");
  {
    MovieWriter movie(dir + "/m.mp4", 10);
    for (int k = 0; k < 5; ++k)
      movie.addFrame(gradient(33, 21, k));
    movie.close();
  }
  std::ifstream in(dir + "/m.mp4", std::ios::binary);
  char head[8] = {};
  in.read(head, 8);
  EXPECT_EQ(std::string(head + 4, 4), "ftyp") << "not an ISO media file";
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{ "m.mp4" });
  // ffprobe (installed with ffmpeg) decodes it: H.264, padded to even sizes, every frame there.
  const std::string command = "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                              "stream=codec_name,width,height,r_frame_rate,nb_read_frames "
                              "-of csv=p=0 '" +
                              dir + "/m.mp4'";
  FILE* probe = popen(command.c_str(), "r");
  ASSERT_NE(probe, nullptr);
  char line[256] = {};
  const bool read = std::fgets(line, sizeof line, probe) != nullptr;
  pclose(probe);
  ASSERT_TRUE(read) << "ffprobe printed nothing";
  EXPECT_EQ(std::string(line), "h264,34,22,10/1,5\n");
}

// ---------------------------------------------------------------------------------------------
// VTK's error messages

TEST(VtkMessages, TheSourcesErrorArrivesAsItsMessageAlone)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scenePath("no-such-scene.json").c_str());
  VtkMessageCatcher messages;
  messages.watchAlgorithm(source);
  source->Update();
  ASSERT_TRUE(messages.failed());
  const std::string first = messages.firstError();
  EXPECT_NE(first.find("no-such-scene.json"), std::string::npos) << first;
  EXPECT_EQ(first.find("ERROR: In"), std::string::npos) << first;
  EXPECT_EQ(first.find("vtkGeodesicSource ("), std::string::npos) << first;
  EXPECT_EQ(first.find('\n'), std::string::npos) << first;
}

TEST(VtkMessages, PlainMessageOfEachFraming)
{
  EXPECT_EQ(plainVtkMessage("ERROR: In /x/y.cxx, line 12\nvtkFoo (0x1234): it broke\n\n"),
            "it broke");
  EXPECT_EQ(plainVtkMessage("ERROR: In /x/e.cxx, line 9\nvtkCompositeDataPipeline (0x9): "
                            "Algorithm vtkFoo(0x1) returned failure for request: vtkInformation "
                            "(0x2)\n  Debug: Off\n"),
            "Algorithm vtkFoo(0x1) returned failure for request: vtkInformation (0x2)");
  EXPECT_EQ(plainVtkMessage("plain text"), "plain text");
  EXPECT_EQ(plainVtkMessage("Generic Warning: In /x/g.cxx, line 3\nno object here\n\n"),
            "no object here");
}

namespace
{
/// A warning of an object nobody observes, as VTK's readers emit them while a factory tries them.
void warnUnobserved(const char* text)
{
  vtkNew<vtkPolyData> nobodyWatchesThis;
  vtkWarningWithObjectMacro(nobodyWatchesThis.GetPointer(), << text);
}
}

TEST(VtkMessages, AStrayWarningGoesToTheLiveCatcherThenOnePlainLine)
{
  routeVtkMessages();
  ::testing::internal::CaptureStderr();
  {
    VtkMessageCatcher messages;
    warnUnobserved("a reader had doubts");
    const std::vector<StrayVtkMessage> strays = messages.strays();
    ASSERT_EQ(strays.size(), 1u);
    EXPECT_FALSE(strays[0].error);
    EXPECT_EQ(strays[0].text, "a reader had doubts");
    EXPECT_FALSE(messages.failed()) << "a stray is no error of the work watched";
  }
  // Printed when the catcher ends without a failure: plain, one line, no colour.
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "asrt: VTK warning: a reader had doubts\n");
}

TEST(VtkMessages, StraysAreDroppedWhenTheWorkFails)
{
  routeVtkMessages();
  ::testing::internal::CaptureStderr();
  try
  {
    VtkMessageCatcher messages;
    warnUnobserved("TGA reader: not a TGA file");
    throw std::runtime_error("the texture cannot be read");
  }
  catch (const std::runtime_error&)
  {
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << "only the error's own line belongs";
}

TEST(VtkMessages, WithNoCatcherAliveAStrayIsOnePlainLine)
{
  routeVtkMessages();
  ::testing::internal::CaptureStderr();
  warnUnobserved("nobody is listening");
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "asrt: VTK warning: nobody is listening\n");
  EXPECT_EQ(err.find('\x1b'), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// The camera orbit and ray fans

TEST(CameraOrbit, SceneCameraIsTheDocumentedOne)
{
  // Data/scenes/README.md: Fig. 1's static camera at (0, −30, 8) looking at the hole.
  const CameraPose fig1 = sceneCamera(scenePath("fig1-cylinders.json"));
  EXPECT_EQ(fig1.position, asrt::Vec3(0, -30, 8));
  EXPECT_EQ(fig1.focalPoint, asrt::Vec3(0, 0, 0));
  EXPECT_THROW(sceneCamera(scenePath("no-such-scene.json")), asrt::InvalidParameter);
}

TEST(CameraOrbit, QuarterTurnsAboutZ)
{
  const CameraPose start{ asrt::Vec3(0, -30, 8), asrt::Vec3(1, 0, 0), asrt::Vec3(0, 0, 1) };
  const CameraPose q = turnedAboutZ(start, 90);
  EXPECT_NEAR((q.position - asrt::Vec3(30, 0, 8)).norm(), 0, 1e-12);
  EXPECT_NEAR((q.focalPoint - asrt::Vec3(0, 1, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((q.viewUp - asrt::Vec3(0, 0, 1)).norm(), 0, 1e-12);
  const CameraPose back = turnedAboutZ(turnedAboutZ(start, 123.4), -123.4);
  EXPECT_NEAR((back.position - start.position).norm(), 0, 1e-12);
  EXPECT_DOUBLE_EQ(orbitAngle(3, 4, 360), 270); // a closed orbit does not repeat frame 0
  EXPECT_DOUBLE_EQ(orbitAngle(4, 5, 90), 90);   // a partial one ends where asked
  EXPECT_DOUBLE_EQ(orbitAngle(0, 1, 90), 0);
}

TEST(RayBundle, CrossPixelsAreTheMiddleRowAndColumnOnce)
{
  vtkSmartPointer<vtkIntArray> pixels = crossPixels(41, 31, 2);
  std::set<std::pair<int, int>> seen;
  for (vtkIdType k = 0; k < pixels->GetNumberOfTuples(); ++k)
  {
    const int i = pixels->GetTypedComponent(k, 0), j = pixels->GetTypedComponent(k, 1);
    EXPECT_TRUE(i == 20 || j == 15) << i << ", " << j;
    EXPECT_TRUE(seen.insert({ i, j }).second) << "pixel " << i << ", " << j << " twice";
  }
  EXPECT_EQ(seen.size(), 21u + 16u); // i = 0, 2, ..., 40 on row 15; j = 0, 2, ..., 30 on column 20
  EXPECT_EQ(rayColoringFromName("AbsH"), RayColoring::AbsH);
  EXPECT_THROW(rayColoringFromName("colour"), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// The deflection measurement: against Darwin's exact formula, so that `asrt bench` and the
// deflection example report the truth.

TEST(Measurements, DeflectionConvergesToDarwinsFormula)
{
  asrt::IntegratorConfig loose = asrt::integratorPreset("fast");
  asrt::IntegratorConfig tight = asrt::integratorPreset("accurate");
  for (double b : { 6.0, 10.0, 100.0 })
  {
    const Deflection coarse = schwarzschildDeflection(loose, b);
    const Deflection fine = schwarzschildDeflection(tight, b);
    EXPECT_EQ(fine.trace.termination, asrt::Termination::Escaped);
    EXPECT_LT(fine.relativeError(), 1e-8) << "b = " << b;
    EXPECT_LT(fine.relativeError(), coarse.relativeError()) << "b = " << b;
    // Weak field: 4M/b to leading order.
    if (b == 100.0)
    {
      EXPECT_NEAR(fine.measured, 4.0 / b, 0.05 * 4.0 / b);
    }
  }
  EXPECT_THROW(schwarzschildDeflection(tight, 5.0), asrt::InvalidParameter);
}

// ---------------------------------------------------------------------------------------------
// Progress on stderr

namespace
{
/// Everything written to stderr while `f` runs.
template<class F>
std::string stderrOf(F&& f)
{
  std::fflush(stderr);
  char name[] = "/tmp/asrt-stderr-XXXXXX";
  const int fd = mkstemp(name);
  const int saved = dup(STDERR_FILENO);
  dup2(fd, STDERR_FILENO);
  f();
  std::fflush(stderr);
  dup2(saved, STDERR_FILENO);
  close(saved);
  close(fd);
  std::ifstream in(name);
  std::ostringstream os;
  os << in.rdbuf();
  std::remove(name);
  return os.str();
}
}

TEST(Progress, LinesAreSparseAndEndWithTheTime)
{
  const std::string text = stderrOf(
    []
    {
      ProgressBar bar("work", ProgressBar::Style::Lines);
      for (int k = 0; k <= 1000; ++k)
        bar.update(k / 1000.0);
      bar.finish("note");
    });
  int lines = 0;
  for (char c : text)
    lines += c == '\n';
  EXPECT_EQ(lines, 4) << text; // 25 %, 50 %, 75 %, done
  EXPECT_NE(text.find("work: 50%"), std::string::npos) << text;
  EXPECT_NE(text.find("work: done in"), std::string::npos) << text;
  EXPECT_NE(text.find("note"), std::string::npos) << text;
  EXPECT_EQ(text.find('\r'), std::string::npos) << "carriage returns outside a terminal";
}

TEST(Progress, AMovieCountsEachFrameOnceWhicheverWayItIsMade)
{
  // Frames 0, 4 and 8 traced whole while the keys are made, then all nine written in order.
  asrt::tools::FrameCount made(9);
  EXPECT_DOUBLE_EQ(made.share(), 0.0);
  for (int k : { 0, 8, 4 })
    made.made(k);
  EXPECT_DOUBLE_EQ(made.share(), 3.0 / 9.0);
  double last = made.share();
  for (int k = 0; k < 9; ++k)
  {
    const double share = made.made(k);
    // Writing a frame made before adds nothing; making one adds a ninth.
    const bool before = k == 0 || k == 4 || k == 8;
    EXPECT_DOUBLE_EQ(share, last + (before ? 0.0 : 1.0 / 9.0)) << "frame " << k;
    last = share;
  }
  EXPECT_DOUBLE_EQ(made.share(), 1.0);
  EXPECT_THROW(made.made(9), std::out_of_range);
  EXPECT_THROW(made.made(-1), std::out_of_range);
  EXPECT_THROW(asrt::tools::FrameCount(0), std::invalid_argument);
}

TEST(Progress, BarRedrawsInPlaceAndSilentSaysNothing)
{
  const std::string bar = stderrOf(
    []
    {
      ProgressBar b("work", ProgressBar::Style::Bar);
      b.update(0.5);
      b.finish();
    });
  EXPECT_NE(bar.find("\rwork ["), std::string::npos) << bar;
  EXPECT_NE(bar.find("100%"), std::string::npos) << bar;
  const std::string silent = stderrOf(
    []
    {
      ProgressBar b("work", ProgressBar::Style::Silent);
      b.update(0.5);
      b.finish();
    });
  EXPECT_EQ(silent, "");
}
