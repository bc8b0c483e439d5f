// Writing a frame's files: each scene traced once at 1920×1080 (the default preset), then its
// picture, frame (.vti) and hit points (-hits.vtp) written the way asrt trace writes them
// (DataFiles: a temporary made durable, then renamed), with every compression, in one run so that
// the choices compare under the same load: on all threads to a directory on disk, and on one
// thread and on all to a directory in memory (the compression's own pace, without the disk's).
// Prints a Markdown section for bench/REPORT.md.
// Usage: asrt_bench_outputs DISK_DIR MEMORY_DIR SCENE.json... (scratch directories; MEMORY_DIR on
// a tmpfs such as /dev/shm)
#include "DataFiles.h"
#include "vtkGeodesicSource.h"

#include "vtkImageData.h"
#include "vtkPolyData.h"

#include <omp.h>

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

using namespace asrt::tools;

namespace
{
double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double megabytes(const std::string& path)
{
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? static_cast<double>(st.st_size) / 1e6 : 0.0;
}

/// The machine's load average over the last minute (/proc/loadavg), or -1.
double loadAverage()
{
  double load = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r"))
  {
    if (std::fscanf(f, "%lf", &load) != 1)
      load = -1;
    std::fclose(f);
  }
  return load;
}

struct Codec
{
  const char* name;
  XmlCompression compression;
};

const Codec kCodecs[] = { { "zlib (the former default)", XmlCompression::ZLib },
                          { "zlib level 1", XmlCompression::ZLibFastest },
                          { "**LZ4 (the default)**", XmlCompression::LZ4 },
                          { "none", XmlCompression::None } };

/// CPU seconds of the whole process so far, every thread's, user and system.
double cpuNow()
{
  rusage use;
  getrusage(RUSAGE_SELF, &use);
  auto seconds = [](const timeval& t)
  { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(use.ru_utime) + seconds(use.ru_stime);
}

struct Timing
{
  double wall = 1e300, cpu = 0;
};

/// "W s (C s CPU)"
std::string cell(const Timing& t)
{
  char text[64];
  std::snprintf(text, sizeof text, "%.2f s (%.2f s CPU)", t.wall, t.cpu);
  return text;
}

/// Wall and CPU seconds to write one file, the repetition of `repeat` with the least wall time,
/// the file removed after each.
Timing timeWrite(const std::function<void()>& write, const std::string& path, int repeat,
                 double& size)
{
  Timing best;
  for (int k = 0; k < repeat; ++k)
  {
    const double t0 = now(), c0 = cpuNow();
    write();
    const double wall = now() - t0, cpu = cpuNow() - c0;
    if (wall < best.wall)
      best = { wall, cpu };
    size = megabytes(path);
    unlink(path.c_str());
  }
  return best;
}

void benchScene(const std::string& disk, const std::string& memory, const std::string& scene,
                int threads)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene.c_str());
  source->SetResolution(1920, 1080);
  const double t0 = now();
  source->Update();
  const double traced = now() - t0;
  vtkImageData* image = source->GetImageOutput();
  vtkPolyData* hits = source->GetHitsOutput();
  std::printf("### `%s` at 1920×1080\n\n", scene.c_str());
  std::printf("Traced in %.1f s on %d threads (default preset); %lld hit points.\n\n", traced,
              threads, static_cast<long long>(hits->GetNumberOfPoints()));
  const std::string png = disk + "/frame.png";
  double size = 0;
  const Timing pngTime = timeWrite([&] { writePng(image, png); }, png, 3, size);
  std::printf("PNG to disk: %s, %.1f MB.\n\n", cell(pngTime).c_str(), size);
  std::printf(
    "| file | compression | size | to disk, %d threads | in memory, 1 thread | in memory, "
    "%d threads |\n|---|---|---|---|---|---|\n",
    threads, threads);
  for (const char* file : { ".vti", "-hits.vtp" })
    for (const Codec& codec : kCodecs)
    {
      const bool isVti = file[0] == '.';
      auto timeIn = [&](const std::string& dir, int t)
      {
        const std::string path = dir + "/frame" + file;
        omp_set_num_threads(t);
        // The hit points take seconds a write: one of each, not the best of three.
        return timeWrite(
          [&]
          {
            if (isVti)
              writeVti(image, path, codec.compression);
            else
              writeVtp(hits, path, codec.compression);
          },
          path, isVti ? 3 : 1, size);
      };
      const Timing onDisk = timeIn(disk, threads);
      const Timing one = timeIn(memory, 1);
      const Timing all = timeIn(memory, threads);
      std::printf("| `%s` | %s | %.1f MB | %s | %s | %s |\n", file, codec.name, size,
                  cell(onDisk).c_str(), cell(one).c_str(), cell(all).c_str());
      std::fflush(stdout);
    }
  std::printf("\n");
}
}

int main(int argc, char** argv)
{
  if (argc < 4)
  {
    std::fprintf(stderr, "usage: %s DISK_DIR MEMORY_DIR SCENE.json...\n", argv[0]);
    return 2;
  }
  const int threads = omp_get_max_threads();
  std::printf("<!-- outputs:begin -->\n## Writing a frame's files\n\n");
  std::printf(
    "Each scene traced once, then its files written as `asrt trace` writes them (a temporary "
    "in the output directory, made durable with fsync, then renamed), with every compression, "
    "in the same run: to the disk on %d threads, and to a tmpfs (`%s`, no disk: the "
    "compression's and encoding's own pace) on 1 thread and on %d. VTK XML inline binary "
    "(base64), whose arrays are compressed in 32 KiB blocks on every thread; the bytes are the "
    "same at any thread count. Times: wall, and in brackets the process's CPU time on all its "
    "threads (which the load of the machine changes less); best of three for the PNG and the "
    "`.vti`, one write for the hit points.\n\n",
    threads, argv[2], threads);
  std::string command = "asrt_bench_outputs";
  for (int k = 1; k < argc; ++k)
    command += std::string(" ") + argv[k];
  std::printf("Command: `%s` (`ASRT_BENCH_ONLY=outputs bench/run` runs it).\n\n", command.c_str());
  const double loadBefore = loadAverage();
  for (int k = 3; k < argc; ++k)
    benchScene(argv[1], argv[2], argv[k], threads);
  std::printf("Load average (1 min) of the machine at the start %.1f, at the end %.1f, on %ld "
              "cores: above the core count, the wall times stretch.\n\n",
              loadBefore, loadAverage(), sysconf(_SC_NPROCESSORS_ONLN));
  std::printf("<!-- outputs:end -->\n");
  return 0;
}
