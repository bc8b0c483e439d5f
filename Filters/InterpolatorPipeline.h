// What the two frame interpolators (vtkGeodesicFrameInterpolator, vtkGeodesicPathInterpolator)
// tell the pipeline alike: their output is a frame-sized RGB image, their inputs are whole untimed
// frames, and each output frame reports the parameters it was made at. Private to ASRT::Filters.
#ifndef asrt_InterpolatorPipeline_h
#define asrt_InterpolatorPipeline_h

#include "FrameMatching.h"
#include "GeodesicRecordArrays.h"

#include "vtkDataObject.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkStreamingDemandDrivenPipeline.h"

namespace asrt
{
/// The output's whole extent (width × height pixels at unit spacing from the origin) and its RGB
/// scalars.
inline void declareFrameImage(vtkInformation* outInfo, int width, int height)
{
  const int ext[6] = { 0, width - 1, 0, height - 1, 0, 0 };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext, 6);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, VTK_UNSIGNED_CHAR, 3);
}

/// Every connection of one input port asked for its whole, untimed data: the frames are not
/// temporal and are needed whole, whatever time or piece is asked of the interpolator.
inline void requestWholeUntimed(vtkInformationVector* port)
{
  for (int k = 0; k < port->GetNumberOfInformationObjects(); ++k)
  {
    vtkInformation* in = port->GetInformationObject(k);
    in->Remove(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
  }
}

/// The parameters a frame was made at, as field data: "Mass", "Spin", "Charge",
/// "CameraPosition", "FocalPoint", "ViewUp".
inline void setParametersFieldData(const FrameParameters& p, vtkFieldData* fd)
{
  setSpacetimeFieldData(p.spacetime, fd);
  addDoubleField(fd, "CameraPosition", { p.position.x(), p.position.y(), p.position.z() });
  addDoubleField(fd, "FocalPoint", { p.focalPoint.x(), p.focalPoint.y(), p.focalPoint.z() });
  addDoubleField(fd, "ViewUp", { p.viewUp.x(), p.viewUp.y(), p.viewUp.z() });
}
}

#endif
