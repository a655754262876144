// tools/bench/mpi.cpp — the distributed method's speed on this machine:
//   - parallel efficiency of dist with 2 children against seq, both timed in this run on
//     the same scene: T_seq / (2 · T_dist), target ≥ 85% of linear;
//   - the parent's overhead for 32×32 frames: its CPU time while distributing (per frame
//     and as a share of the distribution's wall time), and the wall time beyond the ideal
//     split of the children's work.
// The tracers run as `zephyr render` subprocesses (dist under mpirun, next to this binary);
// times come from their JSON reports, so process and MPI start-up are not counted. Prints
// medians of repeats. BENCH_MPI_SPHERES / BENCH_MPI_SIZE / BENCH_MPI_REPEATS override.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace {

std::string Env(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

bool Run(const std::string& command) {
  if (std::system((command + " > /dev/null 2>&1").c_str()) == 0) return true;
  std::fprintf(stderr, "bench_mpi: failed: %s\n", command.c_str());
  return false;
}

nlohmann::json Read(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace

int main() {
  namespace fs = std::filesystem;
  const std::string zephyr = (fs::read_symlink("/proc/self/exe").parent_path() / "zephyr").string();
  const std::string dir =
      (fs::temp_directory_path() / ("bench_mpi_" + std::to_string(getpid()))).string();
  fs::create_directories(dir);
  const std::string spheres = Env("BENCH_MPI_SPHERES", "512"),
                    size = Env("BENCH_MPI_SIZE", "384x384");
  const int repeats = std::atoi(Env("BENCH_MPI_REPEATS", "3").c_str());
  const std::string scene = dir + "/s.nff";
  if (!Run(zephyr + " gen spheres --count " + spheres + " --seed 1 --size " + size + " --out " +
           scene))
    return 1;
  const std::string mpirun = "mpirun -np 3 --oversubscribe --allow-run-as-root " + zephyr;

  std::vector<double> seq, dist, cpuShare, cpuPerFrame, beyondIdeal, busySum;
  int frames = 0;
  for (int r = 0; r < repeats; ++r) {
    if (!Run(zephyr + " render --no-progress --method seq " + scene + " --report " + dir +
             "/seq.json"))
      return 1;
    seq.push_back(Read(dir + "/seq.json")["phases"]["render"].get<double>());
    if (!Run(mpirun + " render --no-progress --method dist --frame 32 " + scene + " --out " + dir +
             "/d.png --report " + dir + "/dist.json"))
      return 1;
    auto d = Read(dir + "/dist.json")["distributed"];
    const double wall = d["time"]["distributionSeconds"].get<double>();
    const double cpu = d["time"]["parentCpuSeconds"].get<double>();
    const double busy = d["time"]["childrenBusySeconds"].get<double>();
    frames = d["frames"]["total"].get<int>();
    dist.push_back(wall);
    cpuShare.push_back(cpu / wall);
    cpuPerFrame.push_back(cpu / frames);
    beyondIdeal.push_back(wall - busy / 2);
    busySum.push_back(busy);
  }
  const double efficiency = Median(seq) / (2 * Median(dist));
  std::printf("scene: %s spheres, %s pixels, depth 5; medians of %d runs\n", spheres.c_str(),
              size.c_str(), repeats);
  std::printf("seq render:                      %8.3f s\n", Median(seq));
  std::printf("dist, 2 children, 32x32 frames:  %8.3f s  (distribution, %d frames)\n", Median(dist),
              frames);
  std::printf("parallel efficiency vs seq:      %8.1f %%  (target >= 85%%)\n", 100 * efficiency);
  std::printf("parent CPU while distributing:   %8.1f %% of the wall time, %.1f us per frame\n",
              100 * Median(cpuShare), 1e6 * Median(cpuPerFrame));
  std::printf("wall time beyond busy/2:         %8.3f s  (farm efficiency busy/(2 wall) %.1f %%)\n",
              Median(beyondIdeal), 100 * Median(busySum) / (2 * Median(dist)));
  std::printf(
      "children's busy time, summed:    %8.3f s  (%.2f x seq: >1 when the cores are shared)\n",
      Median(busySum), Median(busySum) / Median(seq));
  double load[1] = {0};
  if (getloadavg(load, 1) == 1)
    std::printf(
        "load average (1 min) at the end: %8.2f on %ld cores — other work skews the figures\n",
        load[0], sysconf(_SC_NPROCESSORS_ONLN));
  fs::remove_all(dir);
  return 0;
}
