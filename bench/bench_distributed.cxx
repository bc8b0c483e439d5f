// Distributed tracing: strong scaling of one frame over MPI processes, and the load
// balance of row splits at 2 to 64 processes by simulation. Two modes:
//
//   mpiexec -np N asrt_bench_distributed run SCENE.json WxH LAYOUT[,LAYOUT...] OUT
//     traces the frame with vtkGeodesicDistributedSource once per layout (interleaved,
//     contiguous) on the N processes, each with $OMP_NUM_THREADS threads, and process 0 writes
//     what it measured to OUT: wall time of the update, every process's integration steps and
//     tracing time, the integration steps of every row, and a digest of the frame (image arrays
//     and every record) that must not depend on the split.
//   asrt_bench_distributed report COMMAND RUN_FILE...
//     prints bench/REPORT.md's section from the run files: the measured runs, and every split of
//     the frame's rows at 2 to 64 processes with the steps each process would take.
#include "DistributedFrame.h"
#include "vtkGeodesicDistributedSource.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkExecutive.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace
{
/// FNV-1a over bytes: a digest to see that frames are the same, not a security hash.
std::uint64_t fnv(const void* data, std::size_t n, std::uint64_t h = 1469598103934665603ull)
{
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < n; ++k)
    h = (h ^ p[k]) * 1099511628211ull;
  return h;
}

/// Digest of every point array of the image, in a fixed order.
std::uint64_t imageDigest(vtkImageData* image)
{
  std::uint64_t h = 1469598103934665603ull;
  for (const char* name : { "Colors", "ObjectId", "ImageOrder", "PathLength", "Termination" })
  {
    vtkDataArray* a = image->GetPointData()->GetArray(name);
    h = fnv(a->GetVoidPointer(0),
            static_cast<std::size_t>(a->GetNumberOfValues()) *
              static_cast<std::size_t>(a->GetDataTypeSize()),
            h);
  }
  return h;
}

/// The sum of the digests of the records (a sum: the records of a process come in its order).
std::uint64_t recordsDigest(vtkPolyData* hits)
{
  std::uint64_t sum = 0;
  vtkPointData* pd = hits->GetPointData();
  std::vector<double> values;
  for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
  {
    values.clear();
    double x[3];
    hits->GetPoint(k, x);
    values.insert(values.end(), x, x + 3);
    for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
      for (int c = 0; c < pd->GetArray(a)->GetNumberOfComponents(); ++c)
        values.push_back(pd->GetArray(a)->GetComponent(k, c));
    sum += fnv(values.data(), values.size() * sizeof(double));
  }
  return sum;
}

/// The 1-minute load average: other work on the machine, which the timings share it with.
double cpuSeconds()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double loadAverage()
{
  double load = -1;
  std::ifstream("/proc/loadavg") >> load;
  return load;
}

int run(int argc, char* argv[])
{
  vtkNew<vtkMPIController> controller;
  controller->Initialize(&argc, &argv);
  vtkMultiProcessController::SetGlobalController(controller);
  const int rank = controller->GetLocalProcessId(), size = controller->GetNumberOfProcesses();
  int width = 0, height = 0;
  if (argc != 6 || std::sscanf(argv[3], "%dx%d", &width, &height) != 2)
  {
    if (rank == 0)
      std::fprintf(stderr, "usage: mpiexec -np N %s run SCENE.json WxH LAYOUTS OUT\n", argv[0]);
    controller->Finalize();
    return 2;
  }
  std::ofstream out;
  if (rank == 0)
    out.open(argv[5]);
  std::stringstream layouts(argv[4]);
  std::string layout;
  int status = 0;
  while (std::getline(layouts, layout, ','))
  {
    vtkNew<vtkGeodesicDistributedSource> source;
    source->SetController(controller);
    source->SetSceneFileName(argv[2]);
    source->SetResolution(width, height);
    source->SetRowLayout(layout == "contiguous" ? vtkGeodesicDistributedSource::CONTIGUOUS
                                                : vtkGeodesicDistributedSource::INTERLEAVED);
    const double load = loadAverage();
    controller->Barrier();
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = cpuSeconds();
    if (!source->GetExecutive()->Update(0))
    {
      status = 1;
      break;
    }
    const double cpu = cpuSeconds() - cpu0;
    controller->Barrier();
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    // The steps of every row, and the records' digest, summed over the processes.
    vtkPolyData* hits = source->GetHitsOutput();
    vtkDataArray* pixel = hits->GetPointData()->GetArray("Pixel");
    vtkDataArray* steps = hits->GetPointData()->GetArray("Steps");
    std::vector<double> rowSteps(static_cast<std::size_t>(height), 0.0), allRows(rowSteps);
    for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
      rowSteps[static_cast<std::size_t>(pixel->GetComponent(k, 1))] += steps->GetComponent(k, 0);
    controller->AllReduce(rowSteps.data(), allRows.data(), height, vtkCommunicator::SUM_OP);
    const long long mine = static_cast<long long>(recordsDigest(hits));
    std::vector<long long> digests(static_cast<std::size_t>(size));
    controller->AllGather(&mine, digests.data(), 1);
    std::vector<double> cpus(static_cast<std::size_t>(size));
    controller->AllGather(&cpu, cpus.data(), 1);
    if (rank != 0)
      continue;
    std::uint64_t records = 0;
    for (long long d : digests)
      records += static_cast<std::uint64_t>(d);
    out << "run " << size << " " << omp_get_max_threads() << " " << layout << " " << width << " "
        << height << " " << seconds << " " << load << " " << std::hex
        << imageDigest(source->GetImageOutput()) << " " << records << std::dec << "\n";
    vtkDoubleArray* work = source->GetRankWork();
    for (vtkIdType p = 0; p < work->GetNumberOfTuples(); ++p)
      out << "process " << p << " " << static_cast<long long>(work->GetComponent(p, 0)) << " "
          << work->GetComponent(p, 2) << " " << cpus[static_cast<std::size_t>(p)] << "\n";
    out << "rows";
    for (double s : allRows)
      out << " " << static_cast<long long>(s);
    out << "\n";
    std::printf("%d x %d threads, %s: %.1f s\n", size, omp_get_max_threads(), layout.c_str(),
                seconds);
    std::fflush(stdout);
  }
  vtkMultiProcessController::SetGlobalController(nullptr);
  controller->Finalize();
  return status;
}

struct Run
{
  int processes = 0, threads = 0;
  std::string layout;
  int width = 0, height = 0;
  double seconds = 0;
  double load = 0;
  std::string imageDigest, recordsDigest;
  std::vector<long long> steps;
  std::vector<double> traceSeconds, cpuSeconds;
  std::vector<std::int64_t> rows;
};

std::vector<Run> readRuns(const std::vector<std::string>& files)
{
  std::vector<Run> runs;
  for (const std::string& file : files)
  {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line))
    {
      std::istringstream words(line);
      std::string kind;
      words >> kind;
      if (kind == "run")
      {
        runs.emplace_back();
        Run& r = runs.back();
        words >> r.processes >> r.threads >> r.layout >> r.width >> r.height >> r.seconds >>
          r.load >> r.imageDigest >> r.recordsDigest;
      }
      else if (kind == "process" && !runs.empty())
      {
        int p;
        long long s;
        double t, c;
        words >> p >> s >> t >> c;
        runs.back().cpuSeconds.push_back(c);
        runs.back().steps.push_back(s);
        runs.back().traceSeconds.push_back(t);
      }
      else if (kind == "rows" && !runs.empty())
      {
        long long s;
        while (words >> s)
          runs.back().rows.push_back(s);
      }
    }
  }
  return runs;
}

double maxOverMean(const std::vector<std::int64_t>& v)
{
  const double sum = static_cast<double>(std::accumulate(v.begin(), v.end(), std::int64_t(0)));
  return sum > 0 ? static_cast<double>(*std::max_element(v.begin(), v.end())) * v.size() / sum
                 : 1.0;
}

int report(int argc, char* argv[])
{
  if (argc < 4)
  {
    std::fprintf(stderr, "usage: %s report COMMAND RUN_FILE...\n", argv[0]);
    return 2;
  }
  const std::vector<Run> all = readRuns(std::vector<std::string>(argv + 3, argv + argc));
  // Each configuration's fastest run, in the order the configurations first ran.
  std::vector<Run> runs;
  std::map<std::string, int> repeats;
  for (const Run& r : all)
  {
    auto same = std::find_if(runs.begin(), runs.end(),
                             [&](const Run& q) {
                               return q.processes == r.processes && q.threads == r.threads &&
                                      q.layout == r.layout;
                             });
    if (same == runs.end())
      runs.push_back(r);
    else if (r.seconds < same->seconds)
      *same = r;
    ++repeats[std::to_string(r.processes) + "x" + std::to_string(r.threads) + r.layout];
  }
  int fewestRepeats = 1 << 30;
  for (const auto& [key, n] : repeats)
    fewestRepeats = std::min(fewestRepeats, n);
  if (runs.empty() || runs[0].rows.empty())
  {
    std::fprintf(stderr, "no runs in the files given\n");
    return 1;
  }
  const Run* baseline = nullptr;
  for (const Run& r : runs)
    if (r.processes == 1 && r.threads == 1)
      baseline = &r;
  bool identical = true;
  for (const Run& r : all)
    identical =
      identical && r.imageDigest == runs[0].imageDigest && r.recordsDigest == runs[0].recordsDigest;
  const std::vector<std::int64_t>& rows = runs[0].rows;
  const int height = static_cast<int>(rows.size());
  const std::int64_t total = std::accumulate(rows.begin(), rows.end(), std::int64_t(0));

  std::printf("<!-- distributed:begin -->\n## Distributed tracing: strong scaling and load "
              "balance\n\n");
  std::printf("One %d×%d frame of `Data/scenes/kerr-disk.json` (Kerr, a = 0.9 M, thin disk, "
              "the default method) traced by `vtkGeodesicDistributedSource` on MPI processes "
              "(OpenMPI, `mpiexec -np N`), each with `OMP_NUM_THREADS` threads, on this machine's "
              "2 cores. Wall time: the source's update, from the first process starting to the "
              "last finishing (tracing, the neighbour rows' exchange, the image assembled on "
              "process 0; no store, no files); the fastest of %d runs of each configuration, the "
              "configurations taking turns. Load before: the machine's 1-minute "
              "load average as the run began (the 2 cores are shared with other work, and so "
              "are the timings). CPU time: each process's, over the update; with one thread "
              "per process, the speed-up by CPU time (1 × 1's over the busiest process's) "
              "estimates what the split gives when each process has a core of its own; it "
              "counts what every process does alike (loading the scene and its texture) and "
              "MPI's busy waiting in the collective steps. Steps: integration steps each process "
              "took. The frame is the same "
              "in every run: digests of the image arrays "
              "and of every record %s.\n\n",
              runs[0].width, height, fewestRepeats, identical ? "agree" : "**differ**");
  double allSeconds = 0;
  std::printf(
    "| processes × threads | rows | wall time | speed-up over 1 × 1 | speed-up by CPU time "
    "| steps max/mean | per process: tracing wall time / update CPU time | load before "
    "|\n|---|---|---|---|---|---|---|---|\n");
  for (const Run& r : runs)
  {
    std::vector<std::int64_t> steps(r.steps.begin(), r.steps.end());
    std::string perProcess;
    for (std::size_t p = 0; p < r.traceSeconds.size(); ++p)
    {
      char text[48];
      std::snprintf(text, sizeof text, "%s%.1f / %.1f s", perProcess.empty() ? "" : ", ",
                    r.traceSeconds[p], r.cpuSeconds[p]);
      perProcess += text;
    }
    char speedUp[32] = "", cpuSpeedUp[32] = "—";
    if (baseline)
    {
      std::snprintf(speedUp, sizeof speedUp, "%.2f×", baseline->seconds / r.seconds);
      if (r.threads == 1 && !r.cpuSeconds.empty())
        std::snprintf(cpuSpeedUp, sizeof cpuSpeedUp, "%.2f×",
                      baseline->cpuSeconds[0] /
                        *std::max_element(r.cpuSeconds.begin(), r.cpuSeconds.end()));
    }
    std::printf("| %d × %d | %s | %.1f s | %s | %s | %.3f | %s | %.1f |\n", r.processes, r.threads,
                r.processes == 1 ? "all" : r.layout.c_str(), r.seconds, speedUp, cpuSpeedUp,
                maxOverMean(steps), perProcess.c_str(), r.load);
  }
  // Where the work lies: the costliest tenth of the rows, and the band they span.
  std::vector<int> order(static_cast<std::size_t>(height));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return rows[a] > rows[b]; });
  const std::size_t tenth = std::max<std::size_t>(1, order.size() / 10);
  std::int64_t costliest = 0;
  for (std::size_t k = 0; k < tenth; ++k)
    costliest += rows[order[k]];
  const auto [lowest, highest] = std::minmax_element(order.begin(), order.begin() + tenth);
  const auto [cheapRow, dearRow] = std::minmax_element(rows.begin(), rows.end());
  double lowLoad = 1e300, highLoad = 0;
  for (const Run& r : all)
  {
    lowLoad = std::min(lowLoad, r.load);
    highLoad = std::max(highLoad, r.load);
  }
  const unsigned cores = std::thread::hardware_concurrency();
  if (highLoad > cores)
    std::printf("\n**The machine was busy with other work through these runs** (load average "
                "%.1f to %.1f on %u cores): the wall times measure the share of the cores each "
                "run got as much as the split, and CPU times vary by some 10 %% between "
                "repetitions. The steps are exact.\n",
                lowLoad, highLoad, cores);
  std::printf("\nThe frame took %lld integration steps, %.0f per ray on average; a row cost from "
              "%lld to %lld steps. The costliest tenth of the rows (%zu rows, all between rows %d "
              "and %d) took %.0f %% of the steps.\n\n",
              static_cast<long long>(total),
              static_cast<double>(total) / (static_cast<double>(runs[0].width) * height),
              static_cast<long long>(*cheapRow), static_cast<long long>(*dearRow), tenth, *lowest,
              *highest, 100.0 * static_cast<double>(costliest) / static_cast<double>(total));
  std::printf("**Load balance by simulation.** The same frame's rows dealt as N processes would "
              "deal them (`asrt::RowPartition`), each process's work the sum of its rows' "
              "measured steps; max/mean is the slowest process's work over the average, i.e. "
              "the wall time over the ideal with equal processes.\n\n");
  std::printf("| processes | interleaved rows (default) | interleaved blocks of 8 rows | "
              "contiguous bands |\n|---|---|---|---|\n");
  for (int n : { 2, 4, 8, 16, 32, 64 })
  {
    const double interleaved = maxOverMean(asrt::stepsPerRank(asrt::RowPartition(height, n), rows));
    const double blocks = maxOverMean(
      asrt::stepsPerRank(asrt::RowPartition(height, n, asrt::RowLayout::Interleaved, 8), rows));
    const double contiguous = maxOverMean(
      asrt::stepsPerRank(asrt::RowPartition(height, n, asrt::RowLayout::Contiguous), rows));
    std::printf("| %d | %.3f | %.3f | %.3f |\n", n, interleaved, blocks, contiguous);
  }
  for (const Run& r : all)
    allSeconds += r.seconds;
  std::printf("\nThe %zu runs took %.0f s of updates together. Command: `%s`.\n"
              "<!-- distributed:end -->\n",
              all.size(), allSeconds, argv[2]);
  return identical ? 0 : 1;
}
}

int main(int argc, char* argv[])
{
  if (argc >= 2 && std::strcmp(argv[1], "run") == 0)
    return run(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "report") == 0)
    return report(argc, argv);
  std::fprintf(stderr, "usage: %s run ... | report ...\n", argv[0]);
  return 2;
}
