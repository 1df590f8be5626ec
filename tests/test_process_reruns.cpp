// dps-process run as a batch system runs it: the same drive processed twice, with one and with
// five OpenCV threads, in a batch with --jobs 2, and killed with SIGKILL in the middle and then
// run again, always gives byte-identical outputs (timings in summary.json aside), and a killed run
// leaves nothing under the final name and no temporary folder after the next run.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "check.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTools = DPS_TOOLS_DIR;
const fs::path kWork = fs::temp_directory_path() / ("dps_process_reruns_" + std::to_string(::getpid()));

std::string Slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// summary.json without the lines that measure time.
std::string SummaryWithoutTimes(const fs::path& p) {
  std::istringstream in(Slurp(p));
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.find("\"seconds\"") != std::string::npos || line.find("\"frames_per_second\"") != std::string::npos ||
        line.find("\"stage_seconds\"") != std::string::npos) {
      continue;
    }
    out += line + "\n";
  }
  return out;
}

// Every file of two output folders equal (summary.json up to timings); returns the files compared.
// `data_only`: only the CSV files and the masks (the map and summary name the drive).
int CompareOutputs(const fs::path& a, const fs::path& b, const std::string& label, bool data_only = false) {
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    if (data_only && rel.extension() != ".csv" && rel.extension() != ".png") continue;
    CHECK(fs::exists(b / rel));
    if (!fs::exists(b / rel)) continue;
    const bool same = rel == "summary.json" ? SummaryWithoutTimes(e.path()) == SummaryWithoutTimes(b / rel)
                                            : Slurp(e.path()) == Slurp(b / rel);
    if (!same) std::fprintf(stderr, "%s: %s differs\n", label.c_str(), rel.string().c_str());
    CHECK(same);
    ++compared;
  }
  std::printf("%s: %d files identical\n", label.c_str(), compared);
  return compared;
}

int Run(const std::string& command) { return WEXITSTATUS(std::system((command + " > /dev/null 2>&1").c_str())); }

std::string Process(const std::string& drives, const fs::path& out, const std::string& extra = "") {
  return (kTools / "dps-process").string() + " " + drives + " --out '" + out.string() + "' --quiet " + extra;
}

// Starts dps-process on `drive` into `out`, waits until its temporary folder holds part of the
// work, kills it with SIGKILL, and returns whether it was killed before it finished.
bool KillMidway(const fs::path& drive, const fs::path& out) {
  fs::create_directories(out);
  std::fflush(stdout);  // the child's freopen would write what is buffered a second time
  const pid_t child = fork();
  if (child == 0) {
    const std::string tool = (kTools / "dps-process").string(), d = drive.string(), o = out.string();
    freopen("/dev/null", "w", stdout);
    freopen("/dev/null", "w", stderr);
    execl(tool.c_str(), tool.c_str(), d.c_str(), "--out", o.c_str(), "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  const fs::path tmp = out / (".d.tmp-" + std::to_string(child));
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
    if (fs::exists(tmp / "masks")) break;  // the masks are written before the first frame
    int status = 0;
    if (waitpid(child, &status, WNOHANG) == child) return false;  // finished already
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

}  // namespace

int main() {
  fs::create_directories(kWork);
  const fs::path drive = kWork / "drives" / "d";
  CHECK_EQ(Run((kTools / "dps-synth").string() + " " + DPS_SOURCE_DIR + "/data/scenes/overtaking.yaml --size 320x240 --frames 40 --out '" +
               drive.string() + "' --quiet"),
           0);
  CHECK_EQ(Run(Process("'" + drive.string() + "'", kWork / "first")), 0);
  // Run again.
  CHECK_EQ(Run(Process("'" + drive.string() + "'", kWork / "again")), 0);
  CHECK(CompareOutputs(kWork / "first" / "d", kWork / "again" / "d", "rerun") >= 5);
  // With one OpenCV worker thread and with five (OpenCV reads OPENCV_FOR_THREADS_NUM at start):
  // every parallel loop splits its work differently, the outputs stay the same.
  for (const int threads : {1, 5}) {
    const std::string name = "threads" + std::to_string(threads);
    CHECK_EQ(Run("OPENCV_FOR_THREADS_NUM=" + std::to_string(threads) + " " + Process("'" + drive.string() + "'", kWork / name)), 0);
    CHECK(CompareOutputs(kWork / "first" / "d", kWork / name / "d", std::to_string(threads) + " OpenCV thread(s)") >= 5);
  }
  // In a batch of two drives with two jobs.
  fs::copy(drive, kWork / "drives" / "e", fs::copy_options::recursive);
  CHECK_EQ(Run(Process("'" + drive.string() + "' '" + (kWork / "drives" / "e").string() + "'", kWork / "jobs", "--jobs 2")), 0);
  CHECK(CompareOutputs(kWork / "first" / "d", kWork / "jobs" / "d", "--jobs 2, first drive") >= 5);
  CHECK(CompareOutputs(kWork / "first" / "d", kWork / "jobs" / "e", "--jobs 2, second drive (another name)", true) >= 4);
  // Killed with SIGKILL midway: nothing under the final name, its temporary folder left; the next
  // run cleans it and gives the uninterrupted run's outputs.
  const fs::path killed = kWork / "killed";
  const bool was_killed = KillMidway(drive, killed);
  std::printf("killed midway: %s\n", was_killed ? "yes" : "no (it finished first)");
  CHECK(was_killed);
  CHECK(!fs::exists(killed / "d"));
  int temporaries = 0;
  for (const auto& e : fs::directory_iterator(killed)) temporaries += e.path().filename().string().rfind(".d.tmp-", 0) == 0;
  CHECK_EQ(temporaries, 1);
  CHECK_EQ(Run(Process("'" + drive.string() + "'", killed)), 0);
  CHECK(CompareOutputs(kWork / "first" / "d", killed / "d", "after SIGKILL and a rerun") >= 5);
  temporaries = 0;
  for (const auto& e : fs::directory_iterator(killed)) temporaries += e.path().filename().string().find(".tmp-") != std::string::npos;
  CHECK_EQ(temporaries, 0);
  fs::remove_all(kWork);
  return dps_test::Report();
}
