// Texture loading in the VTK layer (vtkGeodesicSource::LoadImagePixels) against VTK's own
// writers and readers: PNGs written by vtkPNGWriter come back pixel for pixel, galaxy.png decodes
// as vtkPNGReader decodes it; hostile PNGs (the first third of galaxy.png, a 60000² header) are
// refused with the file named, and non-PNG formats have their declared size checked before VTK
// reads their pixels. The scene text of the filter goes through the bounded parser too.
#include "FiltersTestUtilities.h"

#include "../Tracing/AddressSpaceLimit.h"
#include "SceneFile.h"

#include "vtkImageData.h"
#include "vtkJPEGWriter.h"
#include "vtkOutputWindow.h"
#include "vtkPNGReader.h"
#include "vtkPNGWriter.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnsignedShortArray.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <utility>

#include <sys/stat.h>

using asrt::testing::MessageCatcher;
using asrt::testing::readFile;
using asrt::testing::texturePath;

namespace
{
std::string tempPath(const std::string& name)
{
  return ::testing::TempDir() + "asrt-loading-" + name;
}

std::string hostilePath(const std::string& name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Testing/Data/hostile/" + name;
}

/// A w × h image of `components` random samples of `Array`'s type.
template<typename Array>
vtkSmartPointer<vtkImageData> randomImage(int w, int h, int components, unsigned seed)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(w, h, 1);
  vtkNew<Array> samples;
  samples->SetNumberOfComponents(components);
  samples->SetNumberOfTuples(static_cast<vtkIdType>(w) * h);
  std::mt19937 random(seed);
  const double top = samples->GetDataTypeMax();
  for (vtkIdType k = 0; k < samples->GetNumberOfValues(); ++k)
    samples->SetValue(k, static_cast<typename Array::ValueType>(random() % (1 + (long)top)));
  image->GetPointData()->SetScalars(samples);
  return image;
}

struct Loaded
{
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

Loaded load(const std::string& path)
{
  Loaded px;
  vtkGeodesicSource::LoadImagePixels(path, px.width, px.height, px.rgb);
  return px;
}

std::string errorOf(const std::string& path)
{
  try
  {
    load(path);
  }
  catch (const asrt::InvalidParameter& e)
  {
    return e.what();
  }
  return "(no error)";
}

/// Counts the image's pixels whose RGB differs from `px` (row 0 at the bottom in both), the
/// expected value of each sample given by `expected`.
template<typename Expected>
int differing(vtkImageData* image, const Loaded& px, Expected expected)
{
  vtkDataArray* samples = image->GetPointData()->GetScalars();
  const int nc = samples->GetNumberOfComponents();
  int count = 0;
  for (vtkIdType k = 0; k < samples->GetNumberOfTuples(); ++k)
    for (int c = 0; c < 3; ++c)
      if (px.rgb[3 * k + c] != expected(samples->GetComponent(k, nc >= 3 ? c : 0)))
        ++count;
  return count;
}

/// Writes `image` with vtkPNGWriter, loads it back, expects every pixel.
template<typename Expected>
void expectRoundTrip(vtkImageData* image, const std::string& name, Expected expected)
{
  const std::string path = tempPath(name);
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->SetFileName(path.c_str());
  writer->Write();
  const Loaded px = load(path);
  std::remove(path.c_str());
  int dims[3];
  image->GetDimensions(dims);
  ASSERT_EQ(px.width, dims[0]);
  ASSERT_EQ(px.height, dims[1]);
  ASSERT_EQ(px.rgb.size(), 3u * dims[0] * dims[1]);
  EXPECT_EQ(differing(image, px, expected), 0) << name;
}

/// Records what reaches VTK's output window (the text a user would see on stderr).
class RecordingOutputWindow : public vtkOutputWindow
{
public:
  static RecordingOutputWindow* New() { return new RecordingOutputWindow; }
  void DisplayText(const char* text) override { this->Text += text ? text : ""; }
  std::string Text;
};
}

TEST(TextureLoading, PngWriterOutputComesBackPixelForPixel)
{
  const auto same = [](double v) { return static_cast<unsigned char>(v); };
  expectRoundTrip(randomImage<vtkUnsignedCharArray>(37, 23, 3, 1), "rgb.png", same);
  expectRoundTrip(randomImage<vtkUnsignedCharArray>(19, 41, 4, 2), "rgba.png", same);
  expectRoundTrip(randomImage<vtkUnsignedCharArray>(16, 9, 1, 3), "grey.png", same);
  expectRoundTrip(randomImage<vtkUnsignedCharArray>(9, 16, 2, 4), "grey-alpha.png", same);
  // 16-bit samples: scaled to 8 bits as LoadImagePixels scales every wider integer type.
  expectRoundTrip(randomImage<vtkUnsignedShortArray>(21, 13, 3, 5), "rgb16.png",
                  [](double v)
                  { return static_cast<unsigned char>(std::lround(v * 255 / 65535)); });
}

TEST(TextureLoading, GalaxyDecodesAsVtkPngReaderDecodesIt)
{
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(texturePath("galaxy.png").c_str());
  reader->Update();
  const Loaded px = load(texturePath("galaxy.png"));
  ASSERT_EQ(px.width, 1024);
  ASSERT_EQ(px.height, 512);
  EXPECT_EQ(
    differing(reader->GetOutput(), px, [](double v) { return static_cast<unsigned char>(v); }), 0);
}

TEST(TextureLoading, TruncatedGalaxyIsRefusedNamingTheFile)
{
  // vtkPNGReader crashes in its error path on this file (libpng "Read Error").
  const std::string galaxy = readFile(texturePath("galaxy.png"));
  const std::string path = tempPath("truncated-galaxy.png");
  std::ofstream(path, std::ios::binary) << galaxy.substr(0, galaxy.size() / 3);
  EXPECT_EQ(errorOf(path),
            "image file \"" + path + "\" holds corrupt or truncated PNG data (libpng: Read Error)");
  std::remove(path.c_str());
}

TEST(TextureLoading, HostilePngsAreRefused)
{
  const asrt::testing::AddressSpaceLimit bound(2e9);
  const std::string huge = hostilePath("png-huge-header.png");
  EXPECT_EQ(errorOf(huge), "image file \"" + huge +
                             "\" declares 60000 x 60000 pixels; image textures may have at most "
                             "16384 pixels a side");
  for (const char* name : { "png-truncated.png", "png-bad-crc.png", "png-garbage.png" })
    EXPECT_NE(errorOf(hostilePath(name)).find("holds corrupt or truncated PNG data (libpng: "),
              std::string::npos)
      << name;
}

TEST(TextureLoading, JpegsHaveTheirDeclaredSizeCheckedFirst)
{
  // A JPEG that vtkJPEGWriter wrote, its frame header (SOFn: FF Cn, length, precision, height,
  // width) edited to declare 60000 × 60000 pixels: decoding it would allocate 10 GB.
  const std::string path = tempPath("huge.jpg");
  vtkNew<vtkJPEGWriter> writer;
  writer->SetInputData(randomImage<vtkUnsignedCharArray>(16, 16, 3, 4));
  writer->SetFileName(path.c_str());
  writer->Write();
  std::string bytes = readFile(path);
  std::size_t sof = 0; // the first start-of-frame marker: baseline, extended or progressive
  while (sof + 9 < bytes.size() && !(static_cast<unsigned char>(bytes[sof]) == 0xFF &&
                                     (static_cast<unsigned char>(bytes[sof + 1]) & 0xFC) == 0xC0 &&
                                     static_cast<unsigned char>(bytes[sof + 1]) != 0xC3))
    ++sof;
  ASSERT_LT(sof + 9, bytes.size()) << "no frame header";
  for (std::size_t at : { sof + 5, sof + 7 }) // height, then width, big-endian
  {
    bytes[at] = static_cast<char>(60000 >> 8);
    bytes[at + 1] = static_cast<char>(60000 & 0xFF);
  }
  std::ofstream(path, std::ios::binary) << bytes;
  const asrt::testing::AddressSpaceLimit bound(2e9);
  EXPECT_EQ(errorOf(path), "image file \"" + path +
                             "\" declares 60000 x 60000 pixels; image textures may have at most "
                             "16384 pixels a side");
  std::remove(path.c_str());
}

TEST(TextureLoading, FormatsOtherThanPngAndJpegAreRefusedByName)
{
  // A truncated PPM (VTK's reader gives black for the missing pixels) and a MetaImage whose data
  // file is a FIFO (VTK's reader would wait for a writer): neither is opened.
  const std::string ppm = tempPath("short.ppm");
  std::ofstream(ppm, std::ios::binary) << "P6\n4 4\n255\n" << std::string(5, '\x7f');
  const std::string header = tempPath("fifo.mhd"), fifo = tempPath("fifo.raw");
  std::ofstream(header) << "ObjectType = Image\nNDims = 2\nDimSize = 2 2\n"
                           "ElementType = MET_UCHAR\nElementDataFile = "
                        << fifo << "\n";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, ext] : { std::pair<std::string, std::string>{ ppm, ".ppm" },
                                   { header, ".mhd" },
                                   { tempPath("picture.tiff"), ".tiff" } })
    EXPECT_EQ(errorOf(path), "image file \"" + path + "\" is not a PNG or JPEG file (extension \"" +
                               ext + "\"): image textures are PNG (.png) or JPEG (.jpg, .jpeg); " +
                               "convert other images first");
  std::remove(ppm.c_str());
  std::remove(header.c_str());
  std::remove(fifo.c_str());
}

TEST(TextureLoading, VtkReaderErrorsReachTheExceptionNotTheOutputWindow)
{
  // The first third of a JPEG that vtkJPEGWriter wrote: VTK's JPEG reader reports an error.
  const std::string whole = tempPath("whole.jpg"), path = tempPath("truncated.jpg");
  vtkNew<vtkJPEGWriter> writer;
  writer->SetInputData(randomImage<vtkUnsignedCharArray>(64, 64, 3, 6));
  writer->SetFileName(whole.c_str());
  writer->Write();
  const std::string bytes = readFile(whole);
  std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  vtkNew<RecordingOutputWindow> window;
  vtkSmartPointer<vtkOutputWindow> previous = vtkOutputWindow::GetInstance();
  vtkOutputWindow::SetInstance(window);
  const std::string message = errorOf(path);
  vtkOutputWindow::SetInstance(previous);
  EXPECT_EQ(load(whole).width, 64) << "the whole file is readable";
  std::remove(whole.c_str());
  std::remove(path.c_str());
  EXPECT_EQ(message.find("image file \"" + path + "\" cannot be read (libjpeg"), 0u) << message;
  EXPECT_EQ(window->Text, "");
}

TEST(TextureLoading, SceneTextGoesThroughTheBoundedParser)
{
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(source, catcher);
  // 100000 levels deep: refused while parsing, not printed into a message.
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  source->SetSceneText(deep.c_str());
  source->Update();
  EXPECT_TRUE(catcher->Mentions("arrays and objects nested more than 64 levels deep"))
    << catcher->AllErrors();
  EXPECT_EQ(source->GetImageOutput()->GetNumberOfPoints(), 0);
  // Beyond the size cap: a valid scene padded with whitespace.
  catcher->Clear();
  std::string big = readFile(asrt::testing::scenePath("fig2-no-hole.json"));
  big += std::string(asrt::kMaxSceneBytes + 1 - big.size(), ' ');
  source->SetSceneText(big.c_str());
  source->Update();
  EXPECT_TRUE(catcher->Mentions("bytes exceed the 64 MiB a scene may have"))
    << catcher->AllErrors().substr(0, 300);
}

TEST(TextureLoading, SceneFileNameIsReadUpToTheCap)
{
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(source, catcher);
  source->SetSceneFileName("/dev/zero");
  {
    const asrt::testing::AddressSpaceLimit bound(2e9);
    source->Update();
  }
  EXPECT_TRUE(catcher->Mentions("scene file \"/dev/zero\" is larger than 64 MiB"))
    << catcher->AllErrors();
}
