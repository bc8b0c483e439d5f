#include "vtkGeodesicDistributedSource.h"

#include "DistributedFrame.h"
#include "FrameTracer.h"
#include "GeodesicRecordArrays.h"
#include "RayStore.h"
#include "StoreConnection.h"

#include "vtkCommunicator.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPolyData.h"

#include <unistd.h>

#include <chrono>
#include <memory>
#include <optional>
#include <sstream>

vtkStandardNewMacro(vtkGeodesicDistributedSource);
vtkCxxSetObjectMacro(vtkGeodesicDistributedSource, Controller, vtkMultiProcessController);

namespace
{
/// Tag of the point-to-point messages carrying neighbour rows.
constexpr int kNeighbourRowsTag = 7301;

/// An orderly failure of one process, made everyone's by Run::agree.
struct Failure
{
  std::string message;
  bool store = false;
  bool interrupted = false;
  bool happened() const { return !this->message.empty(); }
};

/// The text of a vtkErrorMacro as an ErrorEvent carries it, without VTK's "ERROR: In file, line"
/// framing and "Class (address): " prefix.
std::string plainMessage(const char* eventText)
{
  std::string text = eventText ? eventText : "";
  const std::size_t prefix = text.find("): ");
  if (prefix != std::string::npos)
    text = text.substr(prefix + 3);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
    text.pop_back();
  return text;
}

/// Collects the first error an object reports while it lives (and keeps it from the output
/// window: the caller reports it again, as every process's shared error).
class ErrorCapture
{
public:
  explicit ErrorCapture(vtkObject* object)
    : Object(object)
  {
    this->Tag = object->AddObserver(vtkCommand::ErrorEvent, this, &ErrorCapture::onError);
  }
  ~ErrorCapture() { this->Object->RemoveObserver(this->Tag); }
  const std::string& text() const { return this->Text; }

private:
  void onError(vtkObject*, unsigned long, void* callData)
  {
    if (this->Text.empty())
      this->Text = plainMessage(static_cast<const char*>(callData));
  }
  vtkObject* Object;
  unsigned long Tag = 0;
  std::string Text;
};

double physicalMemory()
{
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? static_cast<double>(pages) * size : 8e9;
}

double secondsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}

/// One update's view of the processes: who we are, and the collective steps.
struct vtkGeodesicDistributedSource::Run
{
  vtkMultiProcessController* Controller;
  int Rank = 0;
  int Size = 1;

  explicit Run(vtkMultiProcessController* controller)
    : Controller(controller && controller->GetNumberOfProcesses() > 1 ? controller : nullptr)
  {
    if (this->Controller)
    {
      this->Rank = this->Controller->GetLocalProcessId();
      this->Size = this->Controller->GetNumberOfProcesses();
    }
  }

  /// Collective: true when no process failed; otherwise every process's `f` becomes the failure
  /// of the lowest-numbered failing process (prefixed with its number unless it is process 0).
  bool agree(Failure& f) const
  {
    if (!this->Controller)
      return !f.happened();
    const int mine = f.happened() ? this->Rank : this->Size;
    int first = this->Size;
    this->Controller->AllReduce(&mine, &first, 1, vtkCommunicator::MIN_OP);
    if (first == this->Size)
      return true;
    int header[3] = { static_cast<int>(f.message.size()), f.store ? 1 : 0, f.interrupted ? 1 : 0 };
    this->Controller->Broadcast(header, 3, first);
    std::vector<char> text(static_cast<std::size_t>(header[0]) + 1, '\0');
    if (this->Rank == first)
      std::copy(f.message.begin(), f.message.end(), text.begin());
    this->Controller->Broadcast(text.data(), header[0], first);
    const std::string message(text.data(), static_cast<std::size_t>(header[0]));
    f.message = first == 0 ? message : "process " + std::to_string(first) + ": " + message;
    f.store = header[1] != 0;
    f.interrupted = header[2] != 0;
    return false;
  }

  /// Collective: process 0's string on every process.
  std::string broadcast(const std::string& s) const
  {
    if (!this->Controller)
      return s;
    long long n = static_cast<long long>(s.size());
    this->Controller->Broadcast(&n, 1, 0);
    std::vector<char> text(static_cast<std::size_t>(n) + 1, '\0');
    if (this->Rank == 0)
      std::copy(s.begin(), s.end(), text.begin());
    this->Controller->Broadcast(text.data(), n, 0);
    return std::string(text.data(), static_cast<std::size_t>(n));
  }

  /// Collective: every process's `values` (the same count on each), process after process.
  std::vector<double> allGather(const std::vector<double>& values) const
  {
    if (!this->Controller)
      return values;
    std::vector<double> all(values.size() * static_cast<std::size_t>(this->Size));
    this->Controller->AllGather(values.data(), all.data(), static_cast<vtkIdType>(values.size()));
    return all;
  }

  /// Collective: what the Jacobians read of the rows that neighbour ours, from the processes
  /// that traced them. Pairs of processes exchange in ascending order of the
  /// pair, which every process follows, so blocking sends cannot wait on each other in a cycle.
  std::vector<asrt::JacobianSample> exchangeNeighbourRows(
    const asrt::RowPartition& partition, const std::vector<asrt::RayRecord>& records,
    int width) const
  {
    std::vector<asrt::JacobianSample> neighbours;
    if (!this->Controller)
      return neighbours;
    for (int peer = 0; peer < this->Size; ++peer)
    {
      const std::vector<int> sendRows = partition.rowsBordering(this->Rank, peer);
      const std::vector<int> receiveRows = partition.rowsBordering(peer, this->Rank);
      if (sendRows.empty() && receiveRows.empty())
        continue;
      std::vector<double> out,
        in(receiveRows.size() * static_cast<std::size_t>(width) * asrt::kJacobianSampleSize);
      asrt::packJacobianSamples(records, sendRows, width, out);
      auto send = [&]
      {
        this->Controller->Send(out.data(), static_cast<vtkIdType>(out.size()), peer,
                               kNeighbourRowsTag);
      };
      auto receive = [&]
      {
        this->Controller->Receive(in.data(), static_cast<vtkIdType>(in.size()), peer,
                                  kNeighbourRowsTag);
      };
      if (peer < this->Rank)
      {
        receive();
        send();
      }
      else
      {
        send();
        receive();
      }
      asrt::unpackJacobianSamples(in, receiveRows, width, neighbours);
    }
    return neighbours;
  }

  /// Collective: every process's image samples, concatenated at process 0 (empty elsewhere).
  std::vector<double> gatherAtZero(const std::vector<double>& samples) const
  {
    if (!this->Controller)
      return samples;
    const long long mine = static_cast<long long>(samples.size());
    std::vector<long long> lengths(static_cast<std::size_t>(this->Size));
    this->Controller->AllGather(&mine, lengths.data(), 1);
    std::vector<vtkIdType> counts(lengths.begin(), lengths.end()), offsets(counts.size(), 0);
    for (std::size_t k = 1; k < counts.size(); ++k)
      offsets[k] = offsets[k - 1] + counts[k - 1];
    std::vector<double> all;
    if (this->Rank == 0)
      all.resize(static_cast<std::size_t>(offsets.back() + counts.back()));
    this->Controller->GatherV(samples.data(), all.data(), static_cast<vtkIdType>(samples.size()),
                              counts.data(), offsets.data(), 0);
    return all;
  }
};

vtkGeodesicDistributedSource::vtkGeodesicDistributedSource()
{
  this->SetController(vtkMultiProcessController::GetGlobalController());
  this->RankWork = vtkSmartPointer<vtkDoubleArray>::New();
  this->RankWork->SetName("RankWork");
  this->RankWork->SetNumberOfComponents(4);
  this->RankWork->SetComponentName(0, "Steps");
  this->RankWork->SetComponentName(1, "Rays");
  this->RankWork->SetComponentName(2, "TraceSeconds");
  this->RankWork->SetComponentName(3, "StoreSeconds");
}

vtkGeodesicDistributedSource::~vtkGeodesicDistributedSource()
{
  this->SetController(nullptr);
  this->SetConnectionString(nullptr);
  this->SetLabel(nullptr);
}

vtkDoubleArray* vtkGeodesicDistributedSource::GetRankWork()
{
  return this->RankWork;
}

int vtkGeodesicDistributedSource::RequestInformation(vtkInformation* request,
                                                     vtkInformationVector** inputVector,
                                                     vtkInformationVector* outputVector)
{
  // Loading the scene can fail on one process alone (a texture missing on its machine); the
  // others must not go on to trace and wait for it.
  Failure failure;
  {
    ErrorCapture capture(this);
    if (!this->Superclass::RequestInformation(request, inputVector, outputVector))
      failure.message = capture.text().empty() ? "the scene could not be loaded" : capture.text();
  }
  if (Run(this->Controller).agree(failure))
    return 1;
  vtkErrorMacro(<< failure.message);
  for (int port = 0; port < 3; ++port)
    if (vtkDataObject* out = vtkDataObject::GetData(outputVector, port))
      out->Initialize();
  return 0;
}

/// One RequestData: its state, and its phases in the order it runs them. A phase returning a
/// bool is collective: false when any process failed, every process then holding the same
/// failure (Run::agree).
struct vtkGeodesicDistributedSource::DataRequest
{
  vtkGeodesicDistributedSource* source;
  vtkImageData* image;
  vtkPolyData* hits;
  const Run run;
  Failure failure;
  std::optional<asrt::SceneDescription> scene;
  std::unique_ptr<asrt::FrameTracer> tracer;
  std::optional<asrt::RowPartition> partition;
  std::unique_ptr<asrt::RayStore> store;
  std::int64_t frameId = -1;
  std::vector<asrt::RayRecord> records;
  double traceSeconds = 0, storeSeconds = 0;

  DataRequest(vtkGeodesicDistributedSource* self, vtkImageData* imageOutput,
              vtkPolyData* hitsOutput)
    : source(self)
    , image(imageOutput)
    , hits(hitsOutput)
    , run(this->source->Controller)
  {
  }

  /// Reports the agreed failure and leaves the outputs empty.
  int fail(const std::string& message)
  {
    vtkErrorWithObjectMacro(this->source, << message);
    this->source->StoreFailed = this->failure.store;
    this->source->Interrupted = this->failure.interrupted;
    this->image->Initialize();
    this->hits->Initialize();
    return 0;
  }

  /// fail, once a frame may have been begun: a begun frame must not stay behind half-written.
  /// Except when the frame we joined already had tiles: another run is writing it (or was, and
  /// died), and only its owner, or whoever cleans up abandoned frames, may delete it.
  int failAndForget(const std::string& message)
  {
    const bool othersFrame = message.find("already written") != std::string::npos;
    if (this->store && this->run.Rank == 0 && !othersFrame)
    {
      try
      {
        this->store->deleteFrame(this->frameId);
      }
      catch (const std::exception&)
      {
        // The frame stays 'writing', invisible; abandonedFrames() finds it.
      }
    }
    if (othersFrame)
      return this->fail(message + " (frame " + std::to_string(this->frameId) +
                        " was begun by another run: if that run died, RayStore::abandonedFrames "
                        "finds it and deleteFrame removes it)");
    return this->fail(message);
  }

  /// The scene exactly as RequestInformation loaded it on every process, its tracer and the
  /// rows each process traces; refused when this process's share would not fit in memory.
  bool prepare()
  {
    if (!this->source->Cache)
      this->failure.message = "the scene was not loaded";
    else if (this->source->GetPixelSubset())
      this->failure.message =
        "PixelSubset is not supported in distributed tracing: it traces whole frames";
    else if (this->source->GeneratePolylines)
      this->failure.message = "GeneratePolylines is not supported in distributed tracing";
    if (!this->failure.happened())
    {
      try
      {
        this->scene = *this->source->Cache;
        this->tracer = std::make_unique<asrt::FrameTracer>(*this->scene);
        // On the adaptive grid, interleaved blocks are whole rows of lattice blocks: a process
        // then works through its own lattice blocks (AdaptiveGrid.h), not through every block
        // its rows cross. The frame is the same either way.
        int rowsPerBlock = this->source->RowsPerBlock;
        const int lattice = asrt::effectiveGridLattice(this->scene->rendering);
        if (lattice > 1)
          rowsPerBlock = (rowsPerBlock + lattice - 1) / lattice * lattice;
        this->partition.emplace(this->scene->camera.height, this->run.Size,
                                this->source->RowLayout == CONTIGUOUS
                                  ? asrt::RowLayout::Contiguous
                                  : asrt::RowLayout::Interleaved,
                                rowsPerBlock);
        this->checkMemory();
      }
      catch (const std::exception& e)
      {
        this->failure.message = e.what();
      }
    }
    return this->run.agree(this->failure);
  }

  /// Each process holds its rays' records and hit points; process 0 also the samples of the
  /// whole image while it assembles it.
  void checkMemory()
  {
    const asrt::CameraParameters& camera = this->scene->camera;
    const double own = static_cast<double>(camera.width) *
                       this->partition->rowsOf(this->run.Rank).size(),
                 all = static_cast<double>(camera.width) * camera.height;
    const double bytes = own * (sizeof(asrt::RayRecord) + 352.0) +
                         (this->run.Rank == 0 ? all * (sizeof(asrt::RayRecord) + 104.0) : 0.0);
    const double limit =
      this->source->MemoryLimit > 0.0 ? this->source->MemoryLimit : 0.8 * physicalMemory();
    if (bytes > limit)
    {
      std::ostringstream os;
      os << "process " << this->run.Rank << " needs about " << bytes / 1e9
         << " GB for its share of the frame, more than the " << limit / 1e9 << " GB allowed";
      this->failure.message = os.str();
    }
  }

  /// The store first: an unreachable database should not cost a trace. Process 0 resolves the
  /// connection (it may start the private server) and every process joins the same frame.
  bool beginStoredFrame()
  {
    std::string conninfo;
    if (this->run.Rank == 0)
    {
      try
      {
        conninfo = asrt::storeConnection(this->source->ConnectionString);
      }
      catch (const std::exception& e)
      {
        this->failure = { std::string("cannot start the private PostgreSQL server: ") + e.what(),
                          true };
      }
    }
    if (!this->run.agree(this->failure))
      return false;
    conninfo = this->run.broadcast(conninfo);
    try
    {
      this->store = std::make_unique<asrt::RayStore>(conninfo);
      this->store->migrate();
      this->frameId =
        this->store->beginTiledFrame(*this->scene, this->source->Label ? this->source->Label : "",
                                     this->partition->blockCount(), this->source->ReplaceExisting);
    }
    catch (const std::exception& e)
    {
      this->failure = { e.what(), true };
    }
    if (!this->run.agree(this->failure))
      return false;
    const std::vector<double> ids = this->run.allGather({ static_cast<double>(this->frameId) });
    for (double id : ids)
      if (id != static_cast<double>(this->frameId))
        this->failure = { "the processes began different frames (" +
                            std::to_string(static_cast<long long>(id)) + " and " +
                            std::to_string(this->frameId) + ")",
                          true };
    return this->run.agree(this->failure);
  }

  /// Traces this process's rows.
  bool traceOwnRows()
  {
    const int W = this->scene->camera.width;
    const std::vector<int> rows = this->partition->rowsOf(this->run.Rank);
    std::vector<std::pair<int, int>> pixels;
    pixels.reserve(rows.size() * static_cast<std::size_t>(W));
    for (int j : rows)
      for (int i = 0; i < W; ++i)
        pixels.emplace_back(i, j);
    const auto traceStart = std::chrono::steady_clock::now();
    try
    {
      this->records = this->tracer->traceCentres(pixels,
                                                 [this](double f)
                                                 {
                                                   this->source->UpdateProgress(0.8 * f);
                                                   return !this->source->GetAbortExecute();
                                                 });
      if (this->source->GetAbortExecute())
        this->failure = { "interrupted", false, true };
    }
    catch (const std::exception& e)
    {
      this->failure.message = e.what();
    }
    this->traceSeconds = secondsSince(traceStart);
    return this->run.agree(this->failure);
  }

  /// Anti-aliases this process's rows, judged with the neighbouring rows of the others.
  /// Collective: every process agrees on a failure.
  bool antialiasOwnRows(const std::vector<asrt::JacobianSample>& neighbours)
  {
    try
    {
      this->tracer->antialias(this->records, neighbours,
                              [this](double f)
                              {
                                this->source->UpdateProgress(0.8 + 0.02 * f);
                                return !this->source->GetAbortExecute();
                              });
      if (this->source->GetAbortExecute())
        this->failure = { "interrupted", false, true };
    }
    catch (const std::exception& e)
    {
      this->failure.message = e.what();
    }
    return this->run.agree(this->failure);
  }

  /// This process's tiles, one per block of rows, each in its own transaction. Not collective:
  /// a failure is agreed on after the image and the work are shared.
  void storeTiles()
  {
    const int W = this->scene->camera.width;
    const auto storeStart = std::chrono::steady_clock::now();
    if (!this->store)
      return;
    try
    {
      const std::vector<int> blocks = this->partition->blocksOf(this->run.Rank);
      std::size_t first = 0;
      for (std::size_t k = 0; k < blocks.size(); ++k)
      {
        int tile = blocks[k];
        const std::size_t count = static_cast<std::size_t>(this->partition->blockEnd(tile) -
                                                           this->partition->blockBegin(tile)) *
                                  W;
        this->store->writeTile(this->frameId, tile, count,
                               [&](std::size_t n, asrt::RayRecord& r)
                               { r = this->records[first + n]; });
        first += count;
        this->source->InvokeEvent(TileStoredEvent, &tile);
        this->source->UpdateProgress(0.82 + 0.13 * static_cast<double>(k + 1) / blocks.size());
      }
    }
    catch (const std::exception& e)
    {
      this->failure = { e.what(), true };
    }
    this->storeSeconds = secondsSince(storeStart);
  }

  /// Collective: process 0 assembles the image from everyone's samples.
  void assembleImage()
  {
    std::vector<double> samples;
    asrt::packImageSamples(this->records, samples);
    samples = this->run.gatherAtZero(samples);
    if (this->run.Rank == 0)
    {
      const std::vector<asrt::RayRecord> frame = asrt::unpackImageSamples(samples);
      samples = std::vector<double>();
      asrt::recordsToImage(frame, this->scene->camera.width, 0, this->scene->camera.height,
                           this->image);
    }
  }

  /// Collective: every process's work into RankWork, on every process.
  void shareRankWork()
  {
    std::int64_t steps = 0;
    for (const asrt::RayRecord& r : this->records)
      steps += r.steps;
    const std::vector<double> work =
      this->run.allGather({ static_cast<double>(steps), static_cast<double>(this->records.size()),
                            this->traceSeconds, this->storeSeconds });
    vtkDoubleArray* rankWork = this->source->RankWork;
    rankWork->SetNumberOfTuples(this->run.Size);
    for (int p = 0; p < this->run.Size; ++p)
      rankWork->SetTypedTuple(p, work.data() + 4 * p);
  }
};

int vtkGeodesicDistributedSource::RequestData(vtkInformation*, vtkInformationVector**,
                                              vtkInformationVector* outputVector)
{
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  vtkPolyData* hits = vtkPolyData::GetData(outputVector, 1);
  vtkPolyData* lines = vtkPolyData::GetData(outputVector, 2);
  image->Initialize();
  hits->Initialize();
  lines->Initialize();
  this->FrameId = -1;
  this->StoreFailed = false;
  this->Interrupted = false;
  this->RankWork->SetNumberOfTuples(0);

  DataRequest request(this, image, hits);
  if (!request.prepare())
    return request.fail(request.failure.message);
  if (this->StoreFrame && !request.beginStoredFrame())
    return request.fail(request.failure.message);
  // Whatever fails from here on, a begun frame must not stay behind half-written.
  if (!request.traceOwnRows())
    return request.failAndForget(request.failure.message);
  // The Jacobians and the anti-aliasing across the rows other processes traced.
  const std::vector<asrt::JacobianSample> neighbours = request.run.exchangeNeighbourRows(
    *request.partition, request.records, request.scene->camera.width);
  asrt::FrameTracer::computeJacobians(request.records, neighbours);
  if (!request.antialiasOwnRows(neighbours))
    return request.failAndForget(request.failure.message);
  this->UpdateProgress(0.82);
  request.storeTiles();
  request.assembleImage();
  request.shareRankWork();
  if (!request.run.agree(request.failure))
    return request.failAndForget(request.failure.message);

  asrt::recordsToPolyData(request.records, hits);
  asrt::setFrameFieldData(*request.scene, hits->GetFieldData());
  this->FrameId = request.store ? static_cast<vtkIdType>(request.frameId) : -1;
  this->UpdateProgress(1.0);
  return 1;
}

void vtkGeodesicDistributedSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Controller: " << this->Controller << "\n";
  os << indent << "RowLayout: " << (this->RowLayout == CONTIGUOUS ? "contiguous" : "interleaved")
     << "\n";
  os << indent << "RowsPerBlock: " << this->RowsPerBlock << "\n";
  os << indent << "StoreFrame: " << this->StoreFrame << "\n";
  os << indent << "ConnectionString: "
     << (this->ConnectionString && *this->ConnectionString ? "(set)" : "(default)") << "\n";
  os << indent << "Label: " << (this->Label ? this->Label : "") << "\n";
  os << indent << "ReplaceExisting: " << this->ReplaceExisting << "\n";
  os << indent << "FrameId: " << this->FrameId << "\n";
  os << indent << "StoreFailed: " << this->StoreFailed << "\n";
  os << indent << "Interrupted: " << this->Interrupted << "\n";
  os << indent << "RankWork: " << this->RankWork->GetNumberOfTuples() << " processes\n";
}
