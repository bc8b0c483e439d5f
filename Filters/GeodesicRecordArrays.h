// Ray records as VTK data, both ways: the source's outputs, the writer's input, the reader's
// outputs. One place defines the array names, so that the three always agree.
#ifndef asrt_GeodesicRecordArrays_h
#define asrt_GeodesicRecordArrays_h

#include "RayRecord.h"
#include "SceneDescription.h"

#include "vtkSmartPointer.h"

#include <cstddef>
#include <initializer_list>
#include <memory>
#include <vector>

class vtkDataArray;
class vtkFieldData;
class vtkImageData;
class vtkPolyData;

namespace asrt
{
/// A named array of `tuples` tuples of `components` values (uninitialised).
template<class A>
vtkSmartPointer<A> makeArray(const char* name, int components, vtkIdType tuples)
{
  auto a = vtkSmartPointer<A>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}
/// The point array `name` of the hit points, if it has `components` components and a tuple per
/// point; throws InvalidParameter naming it otherwise.
vtkDataArray* requirePointArray(vtkPolyData* hits, const char* name, int components);
/// The frame rows [rowBegin, rowEnd) as an image: RGB "Colors" and "ObjectId", "ImageOrder",
/// "PathLength", "Termination", "RaysPerPixel" (int32); pixels without a record stay black, id
/// −1, termination 0, 0 rays.
void recordsToImage(const std::vector<RayRecord>& records, int width, int rowBegin, int rowEnd,
                    vtkImageData* image);
/// One vertex per record at its hit point, every record field as point data (raysPerPixel as the
/// int32 "RaysPerPixel", traced as the unsigned char "Traced": 1 traced, 0 interpolated by the
/// adaptive grid).
void recordsToPolyData(const std::vector<RayRecord>& records, vtkPolyData* hits);

/// recordsToPolyData a run of records at a time: the arrays of `count` records are made at once,
/// filled as the runs come, and handed to `hits` by finish(), which throws std::logic_error
/// unless exactly `count` records came (as add() does past them).
class HitsBuilder
{
public:
  HitsBuilder(vtkPolyData* hits, vtkIdType count);
  ~HitsBuilder();
  void add(const RayRecord* records, std::size_t count);
  void finish();

private:
  struct Arrays;
  std::unique_ptr<Arrays> A;
};

/// The image and the hit points of the whole rows [rowBegin, rowEnd) of a frame `width` pixels
/// wide, a run of records at a time, the records being those of every pixel in row-major order
/// from (0, rowBegin), all traced (FrameTracer::traceRows's). finish() gives `hits` what
/// recordsToPolyData and `image` what recordsToImage would, except that the image's "ObjectId",
/// "ImageOrder", "PathLength", "Termination" and "RaysPerPixel" are the hits' arrays of these
/// names: for such records they hold the same values in the same order, and a copy would only
/// double them. With `hits` null only the image is made, with arrays of its own. add() throws
/// std::logic_error at a record out of that order or untraced, finish() if some are missing.
class RowsBuilder
{
public:
  RowsBuilder(vtkImageData* image, vtkPolyData* hits, int width, int rowBegin, int rowEnd);
  ~RowsBuilder();
  void add(const RayRecord* records, std::size_t count);
  void finish();

private:
  struct Parts;
  std::unique_ptr<Parts> P;
};

/// The records of hit points (recordsToPolyData's), one at a time: the constructor throws
/// InvalidParameter naming a missing or malformed array, or the first hit point with an unknown
/// termination or a "Traced" value other than 0 or 1; read() then cannot fail, and may be called
/// from several threads at once. Without a "RaysPerPixel" array (hit points made before
/// anti-aliasing) every record gets 1; without a "Traced" array (made before the adaptive grid)
/// every record is traced.
class HitPointRecords
{
public:
  explicit HitPointRecords(vtkPolyData* hits);
  vtkIdType count() const { return this->Count; }
  void read(vtkIdType k, RayRecord& r) const;

private:
  /// One array's values as doubles (vtkDataArray::GetComponent's), read straight from its memory
  /// where it holds doubles, ints, long longs or bytes contiguously, as the source makes them.
  class Column
  {
  public:
    Column() = default;
    explicit Column(vtkDataArray* array);
    double operator()(vtkIdType k, int c) const;
    explicit operator bool() const { return this->Array != nullptr; }

  private:
    vtkDataArray* Array = nullptr;
    const void* Data = nullptr; ///< null: through Array
    int Type = 0;
    int Components = 1;
  };

  vtkIdType Count;
  Column Points, Pixel, Origin, Direction, Momentum, Term, Object, Normal, Uv, Chord, Length,
    Winding, ImageOrder, Steps, MaxH, Color, Jacobian, RaysPerPixel, Traced;
};
/// The inverse of recordsToPolyData (HitPointRecords, every record read).
std::vector<RayRecord> polyDataToRecords(vtkPolyData* hits);
/// Ray paths as polylines, one per path in order, double points with point data "Lambda", "R",
/// "AbsH" and cell data "Pixel" (i, j) and "Termination": vtkGeodesicSource's port 2.
void pathsToPolyData(const std::vector<RayPath>& paths, vtkPolyData* lines);
/// The inverse of pathsToPolyData; throws InvalidParameter naming what is missing or malformed
/// (an array, a cell that is no polyline, an unknown termination).
std::vector<RayPath> polyDataToPaths(vtkPolyData* lines);
/// Adds the field data array `name`: doubles, one tuple of the given values.
void addDoubleField(vtkFieldData* fd, const char* name, std::initializer_list<double> values);
/// Adds the field data array `name`: one vtkIdType, a count of pixels.
void addCountField(vtkFieldData* fd, const char* name, vtkIdType count);
/// The spacetime as field data "Mass", "Spin" and "Charge" (what frames and interpolated frames
/// both report).
void setSpacetimeFieldData(const SpacetimeParameters& st, vtkFieldData* fd);
/// The frame's scene and parameters as field data ("SceneJSON", "Mass", ..., "Resolution").
void setFrameFieldData(const SceneDescription& d, vtkFieldData* fd);
/// The frame's description back from its "SceneJSON", without image textures (nothing the store
/// or an interpolator needs). Throws InvalidParameter if it is missing or invalid.
SceneDescription frameFromFieldData(vtkFieldData* fd);
}

#endif
