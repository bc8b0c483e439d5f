/**
 * @class   vtkGeodesicDistributedSource
 * @brief   traces one frame on every process of a vtkMultiProcessController (e.g. MPI ranks)
 *
 * A vtkGeodesicSource whose frame is shared out between the processes of a controller: every
 * process runs the same pipeline (SPMD, as under `mpirun`) and traces its rows, on its own
 * OpenMP threads. Rows near the photon sphere cost many times more integration steps than the
 * rest and lie in a band around the shadow, so by default the rows are interleaved (row j to
 * process j mod N) rather than cut into contiguous bands; RowLayout and RowsPerBlock choose.
 *
 * The screen-space Jacobians of a pixel read its neighbours in the rows above and below, which
 * another process traced: the processes exchange those rows' surface coordinates, so every record
 * is bit for bit the single-process one.
 *
 * With StoreFrame on, every process streams its rows to PostgreSQL as tiles of the same frame,
 * concurrently (asrt::RayStore::beginTiledFrame with the same arguments on all of them, then one
 * writeTile per block of rows). The frame becomes visible only when every tile is in: if a process
 * dies, no half-frame is ever visible (RayStore::abandonedFrames finds the remains). If a process
 * fails in an orderly way (database error, interruption), all of them report the same error and
 * the partly written frame is deleted. As a block is a tile, the stored frame is in row-major
 * order, the same as a single process stores.
 *
 * Outputs:
 *  - port 0: on process 0, the whole frame, assembled from every process's rows (identical to
 *    vtkGeodesicSource's); empty on the others;
 *  - port 1: on every process, the hit points of the rays it traced (its piece), with the frame's
 *    scene as field data;
 *  - port 2: empty (polylines are not traced in distributed runs).
 *
 * Every process learns the work each did (GetRankWork): integration steps, rays, seconds spent
 * tracing and storing, which is how the load balance is measured.
 *
 * Without a controller (or with one process) it traces alone, still storing as tiles.
 */
#ifndef vtkGeodesicDistributedSource_h
#define vtkGeodesicDistributedSource_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkCommand.h"        // for vtkCommand::UserEvent
#include "vtkGeodesicSource.h"

#include <string> // for std::string

class vtkDoubleArray;
class vtkMultiProcessController;

class ASRTFILTERS_EXPORT vtkGeodesicDistributedSource : public vtkGeodesicSource
{
public:
  static vtkGeodesicDistributedSource* New();
  vtkTypeMacro(vtkGeodesicDistributedSource, vtkGeodesicSource);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Invoked on a process after each tile it stored has been committed; the call data is the
  /// tile's index (int*).
  enum
  {
    TileStoredEvent = vtkCommand::UserEvent + 701
  };

  ///@{
  /// The processes sharing the frame; the global controller by default (none: trace alone).
  virtual void SetController(vtkMultiProcessController*);
  vtkGetObjectMacro(Controller, vtkMultiProcessController);
  ///@}

  enum RowLayouts
  {
    INTERLEAVED = 0, ///< blocks of RowsPerBlock rows dealt round the processes (default)
    CONTIGUOUS = 1   ///< one band of rows per process
  };
  ///@{
  /// How rows are dealt to processes.
  vtkSetClampMacro(RowLayout, int, INTERLEAVED, CONTIGUOUS);
  vtkGetMacro(RowLayout, int);
  void SetRowLayoutToInterleaved() { this->SetRowLayout(INTERLEAVED); }
  void SetRowLayoutToContiguous() { this->SetRowLayout(CONTIGUOUS); }
  ///@}

  ///@{
  /// Rows per interleaved block (default 1): also the rows per stored tile. On the adaptive ray
  /// grid (rendering.gridLattice > 1) it is rounded up to a multiple of the lattice.
  vtkSetClampMacro(RowsPerBlock, int, 1, VTK_INT_MAX);
  vtkGetMacro(RowsPerBlock, int);
  ///@}

  ///@{
  /// Store the frame in PostgreSQL, each process its own tiles (off by default).
  vtkSetMacro(StoreFrame, bool);
  vtkGetMacro(StoreFrame, bool);
  vtkBooleanMacro(StoreFrame, bool);
  ///@}

  ///@{
  /// As for vtkGeodesicPostgreSQLWriter: a libpq conninfo or URI; empty uses the PG* variables
  /// when any is set, else the private embedded server. Process 0 resolves it for all.
  vtkSetStringMacro(ConnectionString);
  vtkGetStringMacro(ConnectionString);
  ///@}

  ///@{
  /// The stored frame's label.
  vtkSetStringMacro(Label);
  vtkGetStringMacro(Label);
  ///@}

  ///@{
  /// Replace a complete stored frame of the same scene and parameters instead of refusing.
  vtkSetMacro(ReplaceExisting, bool);
  vtkGetMacro(ReplaceExisting, bool);
  vtkBooleanMacro(ReplaceExisting, bool);
  ///@}

  /// Id of the frame the last successful update stored; −1 otherwise.
  vtkGetMacro(FrameId, vtkIdType);
  /// Whether the last update failed in the store (connection, duplicate frame, a tile write),
  /// rather than in the scene or the tracing.
  vtkGetMacro(StoreFailed, bool);
  /// Whether the last update was stopped by AbortExecute on some process.
  vtkGetMacro(Interrupted, bool);

  /// The work of each process in the last update: one tuple per process, components "Steps"
  /// (integration steps), "Rays", "TraceSeconds" and "StoreSeconds". The same on every process.
  vtkDoubleArray* GetRankWork();

protected:
  vtkGeodesicDistributedSource();
  ~vtkGeodesicDistributedSource() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  vtkMultiProcessController* Controller = nullptr;
  int RowLayout = INTERLEAVED;
  int RowsPerBlock = 1;
  bool StoreFrame = false;
  char* ConnectionString = nullptr;
  char* Label = nullptr;
  bool ReplaceExisting = false;
  vtkIdType FrameId = -1;
  bool StoreFailed = false;
  bool Interrupted = false;
  vtkSmartPointer<vtkDoubleArray> RankWork;

private:
  vtkGeodesicDistributedSource(const vtkGeodesicDistributedSource&) = delete;
  void operator=(const vtkGeodesicDistributedSource&) = delete;
  struct Run;
  struct DataRequest;
};

#endif
