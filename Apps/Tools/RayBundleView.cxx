#include "RayBundleView.h"

#include "DataFiles.h"
#include "vtkGeodesicSceneGeometry.h"
#include "vtkGeodesicSource.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkCellData.h"
#include "vtkDataSetMapper.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIntArray.h"
#include "vtkInteractorStyleTrackballCamera.h"
#include "vtkLookupTable.h"
#include "vtkMath.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkScalarBarActor.h"
#include "vtkSphereSource.h"
#include "vtkTextActor.h"
#include "vtkTextProperty.h"
#include "vtkThreshold.h"
#include "vtkWindowToImageFilter.h"

#include <X11/Xlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <set>
#include <stdexcept>

namespace asrt
{
namespace tools
{
namespace
{
/// A 3-vector of the traced frame's field data (the effective camera), or `fallback`.
void fieldVector(vtkFieldData* fd, const char* name, double out[3], const double fallback[3])
{
  vtkDataArray* a = fd ? fd->GetArray(name) : nullptr;
  for (int c = 0; c < 3; ++c)
    out[c] = a && a->GetNumberOfComponents() == 3 ? a->GetComponent(0, c) : fallback[c];
}

/// Termination codes (asrt::Termination) and how they are drawn.
struct Ending
{
  int code;
  const char* name;
  double rgb[3];
};
const Ending kEndings[] = { { 1, "escaped", { 0.45, 0.70, 1.00 } },
                            { 2, "captured", { 1.00, 0.30, 0.20 } },
                            { 3, "step budget", { 0.60, 0.60, 0.60 } },
                            { 4, "numerical failure", { 1.00, 0.20, 1.00 } },
                            { 5, "hit an object", { 1.00, 0.85, 0.25 } } };

/// Colours the rays' mapper and returns the scalar bar that explains them.
vtkSmartPointer<vtkScalarBarActor> colourRays(vtkPolyDataMapper* mapper, vtkPolyData* rays,
                                              RayColoring coloring)
{
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
  mapper->ScalarVisibilityOn();
  mapper->SetLookupTable(lut);
  mapper->UseLookupTableScalarRangeOn();
  if (coloring == RayColoring::Termination)
  {
    mapper->SetScalarModeToUseCellFieldData();
    mapper->SelectColorArray("Termination");
    // A legend of the endings these rays had, in a fixed colour each.
    std::set<int> present;
    if (vtkDataArray* codes = rays->GetCellData()->GetArray("Termination"))
      for (vtkIdType k = 0; k < codes->GetNumberOfTuples(); ++k)
        present.insert(static_cast<int>(codes->GetTuple1(k)));
    lut->IndexedLookupOn();
    int k = 0;
    for (const Ending& e : kEndings)
      if (present.count(e.code))
      {
        lut->SetNumberOfTableValues(k + 1);
        lut->SetTableValue(k++, e.rgb[0], e.rgb[1], e.rgb[2]);
        lut->SetAnnotation(vtkVariant(e.code), e.name);
      }
    bar->SetTitle("ray ended");
    return bar;
  }
  const char* array = coloring == RayColoring::AbsH     ? "AbsH"
                      : coloring == RayColoring::Radius ? "R"
                                                        : "Lambda";
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray(array);
  vtkDataArray* values = rays->GetPointData()->GetArray(array);
  double range[2] = { 0.0, 1.0 };
  if (values && values->GetNumberOfTuples() > 0)
    values->GetRange(range);
  if (coloring == RayColoring::AbsH)
  {
    // |H| spans decades and is exactly 0 on the first point: a log scale over the positive part.
    double lo = VTK_DOUBLE_MAX;
    for (vtkIdType k = 0; values && k < values->GetNumberOfTuples(); ++k)
      if (values->GetTuple1(k) > 0.0)
        lo = std::min(lo, values->GetTuple1(k));
    range[1] = std::max(range[1], 1e-300);
    range[0] = lo < range[1] ? lo : range[1] / 10.0;
    lut->SetScaleToLog10();
  }
  if (coloring == RayColoring::Radius)
    range[1] = std::min(range[1], 60.0); // the interesting part: near the hole
  if (range[1] <= range[0])
    range[1] = range[0] + 1.0;
  lut->SetRange(range);
  lut->SetHueRange(0.667, 0.0); // blue (low) to red (high)
  lut->Build();
  bar->SetTitle(coloring == RayColoring::AbsH     ? "|H|"
                : coloring == RayColoring::Radius ? "r (M)"
                                                  : "lambda");
  return bar;
}
}

RayColoring rayColoringFromName(const std::string& name)
{
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  if (n == "termination")
    return RayColoring::Termination;
  if (n == "absh")
    return RayColoring::AbsH;
  if (n == "r")
    return RayColoring::Radius;
  if (n == "lambda")
    return RayColoring::Lambda;
  throw std::invalid_argument("unknown colouring \"" + name +
                              "\" (termination, absh, r or lambda)");
}

vtkSmartPointer<vtkIntArray> crossPixels(int width, int height, int step)
{
  auto pixels = vtkSmartPointer<vtkIntArray>::New();
  pixels->SetNumberOfComponents(2);
  step = std::max(1, step);
  const int midI = width / 2, midJ = height / 2;
  for (int i = 0; i < width; i += step)
  {
    const int ij[2] = { i, midJ };
    pixels->InsertNextTypedTuple(ij);
  }
  for (int j = 0; j < height; j += step)
  {
    const int ij[2] = { midI, j };
    if (j != midJ || midI % step != 0)
      pixels->InsertNextTypedTuple(ij);
  }
  return pixels;
}

vtkSmartPointer<vtkRenderer> makeRayBundleRenderer(vtkGeodesicSource* source,
                                                   const RayBundleStyle& style)
{
  vtkPolyData* rays = source->GetPolylinesOutput();
  if (!rays || rays->GetNumberOfCells() == 0)
    throw std::runtime_error("no rays to draw (trace with polylines on)");
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  renderer->SetBackground(0.10, 0.10, 0.15);

  vtkNew<vtkPolyDataMapper> rayMapper;
  rayMapper->SetInputData(rays);
  vtkSmartPointer<vtkScalarBarActor> bar = colourRays(rayMapper, rays, style.coloring);
  vtkNew<vtkActor> rayActor;
  rayActor->SetMapper(rayMapper);
  rayActor->GetProperty()->SetLineWidth(1.5);
  renderer->AddActor(rayActor);
  bar->SetLookupTable(rayMapper->GetLookupTable());
  bar->SetNumberOfLabels(4);
  bar->SetWidth(0.12);
  bar->SetHeight(0.5);
  bar->SetPosition(0.86, 0.08);
  bar->GetTitleTextProperty()->SetFontSize(14);
  renderer->AddActor2D(bar);

  // The objects, translucent so that rays behind them show; the horizon opaque. Both from the
  // traced scene with the source's mass and spin.
  auto geometry = [source](bool horizon)
  {
    auto g = vtkSmartPointer<vtkGeodesicSceneGeometry>::New();
    g->SetSceneFileName(source->GetSceneFileName());
    g->SetSceneText(source->GetSceneText());
    g->SetMass(source->GetMass());
    g->SetSpin(source->GetSpin());
    g->SetIncludeHorizon(horizon);
    return g;
  };
  if (style.showObjects)
  {
    auto objects = geometry(false);
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputConnection(objects->GetOutputPort());
    mapper->SetScalarModeToUsePointFieldData();
    mapper->SelectColorArray("Colors");
    vtkNew<vtkActor> actor;
    actor->SetMapper(mapper);
    actor->GetProperty()->SetOpacity(style.objectOpacity);
    renderer->AddActor(actor);
  }
  vtkNew<vtkThreshold> horizonOnly; // the horizon is the surface of object id −1
  horizonOnly->SetInputConnection(geometry(true)->GetOutputPort());
  horizonOnly->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_CELLS, "ObjectId");
  horizonOnly->SetLowerThreshold(-1.5);
  horizonOnly->SetUpperThreshold(-0.5);
  horizonOnly->SetThresholdFunction(vtkThreshold::THRESHOLD_BETWEEN);
  vtkNew<vtkDataSetMapper> horizonMapper;
  horizonMapper->SetInputConnection(horizonOnly->GetOutputPort());
  horizonMapper->ScalarVisibilityOff();
  vtkNew<vtkActor> horizon;
  horizon->SetMapper(horizonMapper);
  horizon->GetProperty()->SetColor(0.0, 0.0, 0.0);
  horizon->GetProperty()->SetSpecular(0.3);
  renderer->AddActor(horizon);

  // The eye, where every ray starts.
  vtkFieldData* frame = source->GetHitsOutput() ? source->GetHitsOutput()->GetFieldData() : nullptr;
  const double origin[3] = { 0, 0, 0 }, zUp[3] = { 0, 0, 1 };
  double eye[3], up[3];
  fieldVector(frame, "CameraPosition", eye, origin);
  fieldVector(frame, "ViewUp", up, zUp);
  const double distance = vtkMath::Norm(eye);
  vtkNew<vtkSphereSource> eyeDot;
  eyeDot->SetCenter(eye);
  eyeDot->SetRadius(std::max(0.15, 0.012 * distance));
  vtkNew<vtkPolyDataMapper> eyeMapper;
  eyeMapper->SetInputConnection(eyeDot->GetOutputPort());
  vtkNew<vtkActor> eyeActor;
  eyeActor->SetMapper(eyeMapper);
  eyeActor->GetProperty()->SetColor(1.0, 1.0, 1.0);
  renderer->AddActor(eyeActor);

  if (!style.title.empty())
  {
    vtkNew<vtkTextActor> title;
    title->SetInput(style.title.c_str());
    title->GetTextProperty()->SetFontSize(16);
    title->GetTextProperty()->SetColor(0.9, 0.9, 0.9);
    title->SetDisplayPosition(10, 10);
    renderer->AddActor2D(title);
  }

  // Seen from the side of the line of sight, a little from above: the eye on one side, the hole
  // towards the other, the bending in between.
  double forward[3] = { -eye[0], -eye[1], -eye[2] };
  if (distance > 0.0)
    vtkMath::MultiplyScalar(forward, 1.0 / distance);
  double side[3], lift[3];
  vtkMath::Cross(forward, up, side);
  if (vtkMath::Normalize(side) < 1e-9)
  {
    const double x[3] = { 1, 0, 0 };
    vtkMath::Cross(forward, x, side);
    vtkMath::Normalize(side);
  }
  vtkMath::Cross(side, forward, lift);
  double focal[3], position[3];
  for (int c = 0; c < 3; ++c)
  {
    focal[c] = eye[c] + 0.6 * distance * forward[c];
    position[c] = focal[c] + 1.7 * distance * (0.85 * side[c] + 0.5 * lift[c]);
  }
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(focal);
  camera->SetPosition(position);
  camera->SetViewUp(lift);
  camera->SetViewAngle(40.0);
  renderer->ResetCameraClippingRange();
  return renderer;
}

bool haveDisplay()
{
  // VTK aborts the process when it cannot open the display: ask Xlib first.
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display)
    return false;
  // The connection stays open for the life of the process: an X server resets when its last
  // client leaves (Xvfb under xvfb-run does), and refuses connections while it resets, so closing
  // it here would make VTK's own connection fail moments later.
  static Display* const connection = XOpenDisplay(nullptr);
  return connection != nullptr;
}

namespace
{
void requireDisplay()
{
  if (!haveDisplay())
    throw std::runtime_error(
      "no X display to render into (DISPLAY is unset or unreachable); VTK here renders through "
      "GLX only: run the command under `xvfb-run -a`");
}
}

void renderToPng(vtkRenderer* renderer, int width, int height, const std::string& path)
{
  AtomicFileSet files;
  renderToPng(renderer, width, height, files.add(path));
  files.commit();
}

void renderToPng(vtkRenderer* renderer, int width, int height, TemporaryFile& file)
{
  requireDisplay();
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(4);
  window->SetSize(width, height);
  window->AddRenderer(renderer);
  window->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  writePng(grab->GetOutput(), file);
  window->RemoveRenderer(renderer);
}

void showInteractive(vtkRenderer* renderer, int width, int height, const std::string& windowName)
{
  requireDisplay();
  vtkNew<vtkRenderWindow> window;
  window->SetSize(width, height);
  window->AddRenderer(renderer);
  window->SetWindowName(windowName.c_str());
  vtkNew<vtkRenderWindowInteractor> interactor;
  vtkNew<vtkInteractorStyleTrackballCamera> style;
  interactor->SetInteractorStyle(style);
  interactor->SetRenderWindow(window);
  window->Render();
  interactor->Start();
  window->RemoveRenderer(renderer);
}
}
}
