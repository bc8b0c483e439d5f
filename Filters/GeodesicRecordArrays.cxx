#include "GeodesicRecordArrays.h"

#include "FrameTracer.h" // kParallelRecords
#include "SceneFile.h"

#include "vtkAOSDataArrayTemplate.h"
#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkCellData.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkLongLongArray.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace asrt
{
vtkDataArray* requirePointArray(vtkPolyData* hits, const char* name, int components)
{
  vtkDataArray* a = hits->GetPointData()->GetArray(name);
  if (!a || a->GetNumberOfComponents() != components ||
      a->GetNumberOfTuples() != hits->GetNumberOfPoints())
    throw InvalidParameter(std::string("hit points lack a valid \"") + name + "\" array (" +
                           std::to_string(components) + " components, one tuple per point)");
  return a;
}

namespace
{
std::string requireString(vtkFieldData* fd, const char* name)
{
  auto* a = vtkStringArray::SafeDownCast(fd->GetAbstractArray(name));
  if (!a || a->GetNumberOfValues() < 1)
    throw InvalidParameter(std::string("frame field data lack \"") + name + "\"");
  return a->GetValue(0);
}

/// The 8-bit RGB of a record's colour.
void setColorBytes(vtkUnsignedCharArray* colors, vtkIdType k, const RayRecord& r)
{
  for (int c = 0; c < 3; ++c)
    colors->SetTypedComponent(
      k, c, static_cast<unsigned char>(std::lround(255.0 * std::clamp(r.color[c], 0.0, 1.0))));
}

/// The image's geometry: rows [rowBegin, rowEnd) of `width` pixels, unit spacing from the origin.
void setRowsExtent(vtkImageData* image, int width, int rowBegin, int rowEnd)
{
  int ext[6] = { 0, width - 1, rowBegin, rowEnd - 1, 0, 0 };
  image->Initialize();
  image->SetExtent(ext);
  image->SetSpacing(1, 1, 1);
  image->SetOrigin(0, 0, 0);
}

/// The image's own arrays, "Colors" (its scalars), "ObjectId", "ImageOrder", "PathLength",
/// "Termination" and "RaysPerPixel", one value a pixel.
struct ImageArrays
{
  vtkSmartPointer<vtkUnsignedCharArray> colors;
  vtkSmartPointer<vtkIntArray> objectId, order, termination, raysPerPixel;
  vtkSmartPointer<vtkDoubleArray> pathLength;
  explicit ImageArrays(vtkIdType n)
    : colors(makeArray<vtkUnsignedCharArray>("Colors", 3, n))
    , objectId(makeArray<vtkIntArray>("ObjectId", 1, n))
    , order(makeArray<vtkIntArray>("ImageOrder", 1, n))
    , termination(makeArray<vtkIntArray>("Termination", 1, n))
    , raysPerPixel(makeArray<vtkIntArray>("RaysPerPixel", 1, n))
    , pathLength(makeArray<vtkDoubleArray>("PathLength", 1, n))
  {
  }
  /// Pixels no record reaches: black, no object, not traced.
  void clear()
  {
    this->colors->Fill(0);
    this->objectId->Fill(-1);
    this->order->Fill(0);
    this->pathLength->Fill(0);
    this->termination->Fill(0);
    this->raysPerPixel->Fill(0);
  }
  void set(vtkIdType k, const RayRecord& r)
  {
    setColorBytes(this->colors, k, r);
    this->objectId->SetValue(k, r.objectId);
    this->order->SetValue(k, r.imageOrder);
    this->pathLength->SetValue(k, r.affineLength);
    this->termination->SetValue(k, static_cast<int>(r.termination));
    this->raysPerPixel->SetValue(k, r.raysPerPixel);
  }
  void addTo(vtkPointData* pd) const
  {
    pd->SetScalars(this->colors);
    pd->AddArray(this->objectId);
    pd->AddArray(this->order);
    pd->AddArray(this->pathLength);
    pd->AddArray(this->termination);
    pd->AddArray(this->raysPerPixel);
  }
};
}

void recordsToImage(const std::vector<RayRecord>& records, int width, int rowBegin, int rowEnd,
                    vtkImageData* image)
{
  setRowsExtent(image, width, rowBegin, rowEnd);
  ImageArrays arrays(image->GetNumberOfPoints());
  arrays.clear();
  for (const RayRecord& r : records)
  {
    if (r.termination == Termination::Running || r.j < rowBegin || r.j >= rowEnd || r.i < 0 ||
        r.i >= width)
      continue; // not traced, or outside these rows
    arrays.set(static_cast<vtkIdType>(r.j - rowBegin) * width + r.i, r);
  }
  arrays.addTo(image->GetPointData());
}

struct HitsBuilder::Arrays
{
  vtkPolyData* hits = nullptr;
  vtkIdType count = 0, next = 0;
  vtkSmartPointer<vtkDoubleArray> points;
  vtkSmartPointer<vtkIntArray> pixel, term, object, imageOrder, raysPerPixel;
  vtkSmartPointer<vtkDoubleArray> origin, direction, momentum, normal, uv, chord, length, winding,
    maxH, color, jacobian;
  vtkSmartPointer<vtkLongLongArray> steps;
  vtkSmartPointer<vtkUnsignedCharArray> traced;
};

HitsBuilder::HitsBuilder(vtkPolyData* hits, vtkIdType count)
  : A(std::make_unique<Arrays>())
{
  Arrays& a = *this->A;
  a.hits = hits;
  a.count = count;
  const vtkIdType m = count;
  a.points = makeArray<vtkDoubleArray>("Points", 3, m);
  a.pixel = makeArray<vtkIntArray>("Pixel", 2, m);
  a.origin = makeArray<vtkDoubleArray>("Origin", 3, m);
  a.direction = makeArray<vtkDoubleArray>("Direction", 3, m);
  a.momentum = makeArray<vtkDoubleArray>("Momentum", 4, m);
  a.term = makeArray<vtkIntArray>("Termination", 1, m);
  a.object = makeArray<vtkIntArray>("ObjectId", 1, m);
  a.normal = makeArray<vtkDoubleArray>("HitNormal", 3, m);
  a.uv = makeArray<vtkDoubleArray>("UV", 2, m);
  a.chord = makeArray<vtkDoubleArray>("ChordError", 1, m);
  a.length = makeArray<vtkDoubleArray>("PathLength", 1, m);
  a.winding = makeArray<vtkDoubleArray>("Winding", 1, m);
  a.imageOrder = makeArray<vtkIntArray>("ImageOrder", 1, m);
  a.steps = makeArray<vtkLongLongArray>("Steps", 1, m);
  a.maxH = makeArray<vtkDoubleArray>("MaxAbsH", 1, m);
  a.color = makeArray<vtkDoubleArray>("Color", 3, m);
  a.raysPerPixel = makeArray<vtkIntArray>("RaysPerPixel", 1, m);
  a.jacobian = makeArray<vtkDoubleArray>("Jacobian", 4, m);
  a.traced = makeArray<vtkUnsignedCharArray>("Traced", 1, m);
}

HitsBuilder::~HitsBuilder() = default;

void HitsBuilder::add(const RayRecord* records, std::size_t count)
{
  Arrays& a = *this->A;
  if (static_cast<vtkIdType>(count) > a.count - a.next)
    throw std::logic_error("HitsBuilder: more records than the " + std::to_string(a.count) +
                           " it was made for");
  for (const RayRecord* r = records; r != records + count; ++r)
  {
    const vtkIdType k = a.next++;
    a.points->SetTypedTuple(k, r->hitPoint.data());
    a.pixel->SetTypedComponent(k, 0, r->i);
    a.pixel->SetTypedComponent(k, 1, r->j);
    a.origin->SetTypedTuple(k, r->origin.data());
    a.direction->SetTypedTuple(k, r->direction.data());
    a.momentum->SetTypedTuple(k, r->momentum.data());
    a.term->SetValue(k, static_cast<int>(r->termination));
    a.object->SetValue(k, r->objectId);
    a.normal->SetTypedTuple(k, r->hitNormal.data());
    a.uv->SetTypedComponent(k, 0, r->u);
    a.uv->SetTypedComponent(k, 1, r->v);
    a.chord->SetValue(k, r->chordError);
    a.length->SetValue(k, r->affineLength);
    a.winding->SetValue(k, r->winding);
    a.imageOrder->SetValue(k, r->imageOrder);
    a.steps->SetValue(k, r->steps);
    a.maxH->SetValue(k, r->maxAbsH);
    a.color->SetTypedTuple(k, r->color.data());
    a.raysPerPixel->SetValue(k, r->raysPerPixel);
    const double jac[4] = { r->dudi, r->dudj, r->dvdi, r->dvdj };
    a.jacobian->SetTypedTuple(k, jac);
    a.traced->SetValue(k, r->traced ? 1 : 0);
  }
}

void HitsBuilder::finish()
{
  Arrays& a = *this->A;
  if (a.next != a.count)
    throw std::logic_error("HitsBuilder: " + std::to_string(a.next) + " records of the " +
                           std::to_string(a.count) + " it was made for");
  // One vertex a point, made at its exact size (cells inserted one by one would grow the arrays
  // by doubling).
  auto offsets = makeArray<vtkIdTypeArray>("", 1, a.count + 1);
  auto connectivity = makeArray<vtkIdTypeArray>("", 1, a.count);
  for (vtkIdType k = 0; k < a.count; ++k)
  {
    offsets->SetValue(k, k);
    connectivity->SetValue(k, k);
  }
  offsets->SetValue(a.count, a.count);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(offsets, connectivity);
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetData(a.points);
  vtkPolyData* hits = a.hits;
  hits->Initialize();
  hits->SetPoints(points);
  hits->SetVerts(verts);
  for (vtkDataArray* array : std::initializer_list<vtkDataArray*>{
         a.pixel, a.origin, a.direction, a.momentum, a.term, a.object, a.normal, a.uv, a.chord,
         a.length, a.winding, a.imageOrder, a.steps, a.maxH, a.color, a.raysPerPixel, a.jacobian,
         a.traced })
    hits->GetPointData()->AddArray(array);
}

void recordsToPolyData(const std::vector<RayRecord>& records, vtkPolyData* hits)
{
  HitsBuilder builder(hits, static_cast<vtkIdType>(records.size()));
  builder.add(records.data(), records.size());
  builder.finish();
}

struct RowsBuilder::Parts
{
  vtkImageData* image;
  vtkPolyData* hits;
  int width, rowBegin, rowEnd;
  vtkIdType count, next = 0;
  std::unique_ptr<HitsBuilder> hitArrays; ///< null without hits
  /// The colours; without hits, every array of the image.
  ImageArrays own;
  Parts(vtkImageData* i, vtkPolyData* h, int w, int b, int e)
    : image(i)
    , hits(h)
    , width(w)
    , rowBegin(b)
    , rowEnd(e)
    , count(static_cast<vtkIdType>(w) * (e - b))
    , hitArrays(h ? std::make_unique<HitsBuilder>(h, count) : nullptr)
    , own(h ? 0 : count)
  {
    if (h)
      this->own.colors = makeArray<vtkUnsignedCharArray>("Colors", 3, count);
  }
};

RowsBuilder::RowsBuilder(vtkImageData* image, vtkPolyData* hits, int width, int rowBegin,
                         int rowEnd)
  : P(std::make_unique<Parts>(image, hits, width, rowBegin, rowEnd))
{
}

RowsBuilder::~RowsBuilder() = default;

void RowsBuilder::add(const RayRecord* records, std::size_t count)
{
  Parts& p = *this->P;
  // The image shares the hits' arrays only if the hits are its pixels in order, all traced.
  for (std::size_t k = 0; k < count; ++k)
  {
    const RayRecord& r = records[k];
    const vtkIdType n = p.next + static_cast<vtkIdType>(k);
    const vtkIdType i = n % p.width, j = p.rowBegin + n / p.width;
    if (n >= p.count || r.i != i || r.j != j || r.termination == Termination::Running)
      throw std::logic_error("RowsBuilder: record " + std::to_string(n) +
                             " is not the traced pixel (" + std::to_string(i) + ", " +
                             std::to_string(j) + ") of the rows");
  }
  // Each record fills its own tuples of the preallocated arrays.
  const vtkIdType first = p.next;
  const long n = static_cast<long>(count);
#pragma omp parallel for schedule(static) if (n > kParallelRecords)
  for (long k = 0; k < n; ++k)
  {
    if (p.hitArrays)
      setColorBytes(p.own.colors, first + k, records[k]);
    else
      p.own.set(first + k, records[k]);
  }
  p.next += static_cast<vtkIdType>(count);
  if (p.hitArrays)
    p.hitArrays->add(records, count);
}

void RowsBuilder::finish()
{
  Parts& p = *this->P;
  if (p.hitArrays)
    p.hitArrays->finish();
  else if (p.next != p.count)
    throw std::logic_error("RowsBuilder: " + std::to_string(p.count - p.next) +
                           " records of the rows missing");
  setRowsExtent(p.image, p.width, p.rowBegin, p.rowEnd);
  vtkPointData* pd = p.image->GetPointData();
  if (!p.hitArrays)
  {
    p.own.addTo(pd);
    return;
  }
  pd->SetScalars(p.own.colors);
  for (const char* name : { "ObjectId", "ImageOrder", "PathLength", "Termination", "RaysPerPixel" })
    pd->AddArray(p.hits->GetPointData()->GetArray(name));
}

namespace
{
template<class T>
const void* contiguousValues(vtkDataArray* array)
{
  auto* typed = vtkArrayDownCast<vtkAOSDataArrayTemplate<T>>(array);
  return typed ? static_cast<const void*>(typed->GetPointer(0)) : nullptr;
}
}

HitPointRecords::Column::Column(vtkDataArray* array)
  : Array(array)
  , Type(array->GetDataType())
  , Components(array->GetNumberOfComponents())
{
  switch (this->Type)
  {
    case VTK_DOUBLE:
      this->Data = contiguousValues<double>(array);
      break;
    case VTK_INT:
      this->Data = contiguousValues<int>(array);
      break;
    case VTK_LONG_LONG:
      this->Data = contiguousValues<long long>(array);
      break;
    case VTK_UNSIGNED_CHAR:
      this->Data = contiguousValues<unsigned char>(array);
      break;
    default:
      break;
  }
}

double HitPointRecords::Column::operator()(vtkIdType k, int c) const
{
  const vtkIdType at = k * this->Components + c;
  if (this->Data)
    switch (this->Type)
    {
      case VTK_DOUBLE:
        return static_cast<const double*>(this->Data)[at];
      case VTK_INT:
        return static_cast<double>(static_cast<const int*>(this->Data)[at]);
      case VTK_LONG_LONG:
        return static_cast<double>(static_cast<const long long*>(this->Data)[at]);
      case VTK_UNSIGNED_CHAR:
        return static_cast<double>(static_cast<const unsigned char*>(this->Data)[at]);
      default:
        break;
    }
  return this->Array->GetComponent(k, c);
}

HitPointRecords::HitPointRecords(vtkPolyData* hits)
  : Count(hits->GetNumberOfPoints())
  , Pixel(requirePointArray(hits, "Pixel", 2))
  , Origin(requirePointArray(hits, "Origin", 3))
  , Direction(requirePointArray(hits, "Direction", 3))
  , Momentum(requirePointArray(hits, "Momentum", 4))
  , Term(requirePointArray(hits, "Termination", 1))
  , Object(requirePointArray(hits, "ObjectId", 1))
  , Normal(requirePointArray(hits, "HitNormal", 3))
  , Uv(requirePointArray(hits, "UV", 2))
  , Chord(requirePointArray(hits, "ChordError", 1))
  , Length(requirePointArray(hits, "PathLength", 1))
  , Winding(requirePointArray(hits, "Winding", 1))
  , ImageOrder(requirePointArray(hits, "ImageOrder", 1))
  , Steps(requirePointArray(hits, "Steps", 1))
  , MaxH(requirePointArray(hits, "MaxAbsH", 1))
  , Color(requirePointArray(hits, "Color", 3))
  , Jacobian(requirePointArray(hits, "Jacobian", 4))
{
  if (this->Count > 0)
  {
    vtkPoints* points = hits->GetPoints();
    if (!points || points->GetData()->GetNumberOfComponents() != 3)
      throw InvalidParameter("hit points lack their points");
    this->Points = Column(points->GetData());
  }
  // Hit points made before anti-aliasing have no RaysPerPixel: their pixels had one ray each.
  if (hits->GetPointData()->GetArray("RaysPerPixel"))
    this->RaysPerPixel = Column(requirePointArray(hits, "RaysPerPixel", 1));
  // Hit points made before the adaptive grid have no Traced: every ray of theirs was traced.
  if (hits->GetPointData()->GetArray("Traced"))
    this->Traced = Column(requirePointArray(hits, "Traced", 1));
  // The values a record cannot hold, refused before any is read: the first one, as a reader in
  // order would meet it.
  for (vtkIdType k = 0; k < this->Count; ++k)
  {
    // What read() casts to an int: in range exactly when it lies in (−1, HitObject + 1).
    const double t = this->Term(k, 0);
    if (!(t > -1.0 && t < static_cast<int>(Termination::HitObject) + 1.0))
      throw InvalidParameter(
        "hit point " + std::to_string(k) + " has an unknown termination " +
        (std::abs(t) < 1e9 ? std::to_string(static_cast<long long>(t)) : std::to_string(t)));
    const double flag = this->Traced ? this->Traced(k, 0) : 1.0;
    if (flag != 0.0 && flag != 1.0)
      throw InvalidParameter("hit point " + std::to_string(k) + " has a \"Traced\" value of " +
                             std::to_string(flag) + ", neither 0 (interpolated) nor 1 (traced)");
  }
}

void HitPointRecords::read(vtkIdType k, RayRecord& r) const
{
  for (int c = 0; c < 3; ++c)
  {
    r.hitPoint[c] = this->Points(k, c);
    r.origin[c] = this->Origin(k, c);
    r.direction[c] = this->Direction(k, c);
    r.hitNormal[c] = this->Normal(k, c);
    r.color[c] = this->Color(k, c);
  }
  for (int c = 0; c < 4; ++c)
    r.momentum[c] = this->Momentum(k, c);
  r.i = static_cast<std::int32_t>(this->Pixel(k, 0));
  r.j = static_cast<std::int32_t>(this->Pixel(k, 1));
  r.termination = static_cast<Termination>(static_cast<int>(this->Term(k, 0)));
  r.objectId = static_cast<std::int32_t>(this->Object(k, 0));
  r.u = this->Uv(k, 0);
  r.v = this->Uv(k, 1);
  r.chordError = this->Chord(k, 0);
  r.affineLength = this->Length(k, 0);
  r.winding = this->Winding(k, 0);
  r.imageOrder = static_cast<std::int32_t>(this->ImageOrder(k, 0));
  r.steps = static_cast<std::int64_t>(this->Steps(k, 0));
  r.maxAbsH = this->MaxH(k, 0);
  r.raysPerPixel = this->RaysPerPixel ? static_cast<std::int32_t>(this->RaysPerPixel(k, 0)) : 1;
  r.traced = !this->Traced || this->Traced(k, 0) == 1.0;
  r.dudi = this->Jacobian(k, 0);
  r.dudj = this->Jacobian(k, 1);
  r.dvdi = this->Jacobian(k, 2);
  r.dvdj = this->Jacobian(k, 3);
}

std::vector<RayRecord> polyDataToRecords(vtkPolyData* hits)
{
  const HitPointRecords reader(hits);
  std::vector<RayRecord> records(static_cast<size_t>(reader.count()));
  const long n = static_cast<long>(reader.count());
  // Each record from its own tuples; the pages of the records are first touched here, in
  // parallel too.
#pragma omp parallel for schedule(static) if (n > kParallelRecords)
  for (long k = 0; k < n; ++k)
    reader.read(k, records[static_cast<size_t>(k)]);
  return records;
}

void pathsToPolyData(const std::vector<RayPath>& paths, vtkPolyData* lines)
{
  vtkIdType total = 0;
  for (const RayPath& p : paths)
    total += static_cast<vtkIdType>(p.points.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(total);
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  auto lambda = makeArray<vtkDoubleArray>("Lambda", 1, total);
  auto radius = makeArray<vtkDoubleArray>("R", 1, total);
  auto absH = makeArray<vtkDoubleArray>("AbsH", 1, total);
  const auto n = static_cast<vtkIdType>(paths.size());
  auto pixel = makeArray<vtkIntArray>("Pixel", 2, n);
  auto term = makeArray<vtkIntArray>("Termination", 1, n);
  vtkIdType k = 0;
  std::vector<vtkIdType> ids;
  for (vtkIdType c = 0; c < n; ++c)
  {
    const RayPath& p = paths[static_cast<size_t>(c)];
    ids.clear();
    for (const PathPoint& q : p.points)
    {
      points->SetPoint(k, q.x.data());
      lambda->SetValue(k, q.lambda);
      radius->SetValue(k, q.r);
      absH->SetValue(k, q.absH);
      ids.push_back(k++);
    }
    cells->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
    const int ij[2] = { p.i, p.j };
    pixel->SetTypedTuple(c, ij);
    term->SetValue(c, static_cast<int>(p.termination));
  }
  lines->Initialize();
  lines->SetPoints(points);
  lines->SetLines(cells);
  lines->GetPointData()->AddArray(lambda);
  lines->GetPointData()->AddArray(radius);
  lines->GetPointData()->AddArray(absH);
  lines->GetCellData()->AddArray(pixel);
  lines->GetCellData()->AddArray(term);
}

std::vector<RayPath> polyDataToPaths(vtkPolyData* lines)
{
  const vtkIdType points = lines->GetNumberOfPoints();
  auto pointArray = [&](const char* name)
  {
    vtkDataArray* a = lines->GetPointData()->GetArray(name);
    if (!a || a->GetNumberOfComponents() != 1 || a->GetNumberOfTuples() != points)
      throw InvalidParameter(std::string("polylines lack a valid \"") + name +
                             "\" point array (1 component, one tuple per point)");
    return a;
  };
  vtkDataArray* lambda = pointArray("Lambda");
  vtkDataArray* radius = pointArray("R");
  vtkDataArray* absH = pointArray("AbsH");
  if (lines->GetNumberOfVerts() + lines->GetNumberOfPolys() + lines->GetNumberOfStrips() > 0)
    throw InvalidParameter("polylines: the input has cells that are not lines (vertices, "
                           "polygons or strips)");
  const vtkIdType cells = lines->GetNumberOfLines();
  auto cellArray = [&](const char* name, int components)
  {
    vtkDataArray* a = lines->GetCellData()->GetArray(name);
    if (!a || a->GetNumberOfComponents() != components || a->GetNumberOfTuples() != cells)
      throw InvalidParameter(std::string("polylines lack a valid \"") + name + "\" cell array (" +
                             std::to_string(components) + " components, one tuple per line)");
    return a;
  };
  vtkDataArray* pixel = cellArray("Pixel", 2);
  vtkDataArray* term = cellArray("Termination", 1);
  std::vector<RayPath> paths(static_cast<size_t>(cells));
  auto it = vtkSmartPointer<vtkCellArrayIterator>::Take(lines->GetLines()->NewIterator());
  vtkIdType c = 0;
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++c)
  {
    vtkIdType size = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(size, ids);
    RayPath& p = paths[static_cast<size_t>(c)];
    p.i = static_cast<std::int32_t>(pixel->GetComponent(c, 0));
    p.j = static_cast<std::int32_t>(pixel->GetComponent(c, 1));
    const int t = static_cast<int>(term->GetComponent(c, 0));
    if (t < 0 || t > static_cast<int>(Termination::HitObject))
      throw InvalidParameter("polyline " + std::to_string(c) + " has an unknown termination " +
                             std::to_string(t));
    p.termination = static_cast<Termination>(t);
    p.points.resize(static_cast<size_t>(size));
    for (vtkIdType m = 0; m < size; ++m)
    {
      PathPoint& q = p.points[static_cast<size_t>(m)];
      lines->GetPoint(ids[m], q.x.data());
      q.lambda = lambda->GetComponent(ids[m], 0);
      q.r = radius->GetComponent(ids[m], 0);
      q.absH = absH->GetComponent(ids[m], 0);
    }
  }
  return paths;
}

void addDoubleField(vtkFieldData* fd, const char* name, std::initializer_list<double> values)
{
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(static_cast<int>(values.size()));
  a->InsertNextTuple(values.begin());
  fd->AddArray(a);
}

void addCountField(vtkFieldData* fd, const char* name, vtkIdType count)
{
  auto a = vtkSmartPointer<vtkIdTypeArray>::New();
  a->SetName(name);
  a->InsertNextValue(count);
  fd->AddArray(a);
}

void setSpacetimeFieldData(const SpacetimeParameters& st, vtkFieldData* fd)
{
  addDoubleField(fd, "Mass", { st.mass });
  addDoubleField(fd, "Spin", { st.spin });
  addDoubleField(fd, "Charge", { st.charge });
}

void setFrameFieldData(const SceneDescription& d, vtkFieldData* fd)
{
  auto addString = [fd](const char* name, const std::string& value)
  {
    auto a = vtkSmartPointer<vtkStringArray>::New();
    a->SetName(name);
    a->InsertNextValue(value);
    fd->AddArray(a);
  };
  addString("SceneJSON", effectiveSceneText(d));
  addString("IntegrationMethod", d.integrator.method);
  auto addScalar = [fd](const char* name, std::initializer_list<double> values)
  { addDoubleField(fd, name, values); };
  const CameraParameters& c = d.camera;
  setSpacetimeFieldData(d.spacetime, fd);
  addScalar("CameraPosition", { c.position.x(), c.position.y(), c.position.z() });
  addScalar("FocalPoint", { c.focalPoint.x(), c.focalPoint.y(), c.focalPoint.z() });
  addScalar("ViewUp", { c.viewUp.x(), c.viewUp.y(), c.viewUp.z() });
  addScalar("ViewAngle", { c.viewAngle });
  addScalar("Resolution", { double(c.width), double(c.height) });
  addScalar("IntegrationStep", { d.integrator.step });
  addScalar("Tolerances", { d.integrator.relativeTolerance, d.integrator.absoluteTolerance });
}

SceneDescription frameFromFieldData(vtkFieldData* fd)
{
  // SceneJSON is the effective scene (overrides included): it alone defines the frame.
  return parseSceneWithoutImages(requireString(fd, "SceneJSON"));
}
}
