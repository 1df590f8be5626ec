// Tests of the batch runner (what dps-process runs): a pool of workers over several drives, one
// bad drive reported while the others finish, complete drives skipped, shards of a job array, drive
// lists, and the progress reports with their time estimates.
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "check.h"
#include "fixtures.h"
#include "dps/pipeline/batch.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/synth.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"

namespace fs = std::filesystem;

namespace {

using dps_test::kSource;
const fs::path kTmp = fs::temp_directory_path() / "dps_test_batch";

// Three copies of a short rendered drive and a folder that is no drive.
std::vector<std::string> MakeDrives() {
  dps::Scene scene = dps_test::SmallScene("lead_car", 320, 240);
  dps::SynthOptions so;
  so.frames = 4;
  so.overwrite = true;
  const fs::path first = kTmp / "drives" / "a";
  dps::Synthesize(scene, first.string(), so);
  for (const char* name : {"b", "c"}) fs::copy(first, kTmp / "drives" / name, fs::copy_options::recursive);
  fs::create_directories(kTmp / "drives" / "broken");  // no rig.yaml, no images
  return {first.string(), (kTmp / "drives" / "broken").string(), (kTmp / "drives" / "b").string(),
          (kTmp / "drives" / "c").string()};
}

struct Recorded {
  std::vector<dps::BatchProgress> progress;
  std::vector<std::string> skipped, finished, failed;
};

dps::BatchEvents Record(Recorded* r) {
  dps::BatchEvents e;
  e.progress = [r](const dps::BatchProgress& p) { r->progress.push_back(p); };
  e.skipped = [r](const std::string& dir) { r->skipped.push_back(dir); };
  e.finished = [r](const dps::DriveSummary& s) { r->finished.push_back(s.drive); };
  e.failed = [r](const std::string& drive, const std::string& error) { r->failed.push_back(drive + ": " + error); };
  return e;
}

void TestBatch(const std::vector<std::string>& drives) {
  dps::BatchOptions o;
  o.out_root = (kTmp / "out").string();
  o.jobs = 2;
  o.drive.map_video = false;
  Recorded r;
  const dps::BatchResult first = dps::RunBatch(drives, o, Record(&r));
  CHECK_EQ(first.processed, 3);
  CHECK_EQ(first.failed, 1);
  CHECK_EQ(first.skipped, 0);
  CHECK_EQ(r.finished.size(), size_t{3});
  CHECK_EQ(r.failed.size(), size_t{1});
  if (r.failed.size() != 1) {
    for (const std::string& f : r.failed) std::fprintf(stderr, "failed: %s\n", f.c_str());
  }
  if (!r.failed.empty()) CHECK(r.failed[0].find("broken") != std::string::npos);
  for (const char* name : {"a", "b", "c"}) CHECK(dps::DriveOutputComplete((kTmp / "out" / name).string()));
  CHECK(!fs::exists(kTmp / "out" / "broken"));
  // Progress: every drive reaches its last frame; the batch's estimate falls to 0 at the end.
  std::map<std::string, int> last_frame;
  for (const dps::BatchProgress& p : r.progress) {
    CHECK(p.index >= 1 && p.index <= drives.size());
    CHECK_EQ(p.count, drives.size());
    CHECK(p.frames_per_second > 0 && p.drive_eta_s >= 0 && p.batch_eta_s >= 0);
    last_frame[p.drive] = std::max(last_frame[p.drive], p.frame);
  }
  CHECK_EQ(last_frame.size(), size_t{3});
  for (const auto& [drive, frame] : last_frame) CHECK_EQ(frame, 4);
  if (!r.progress.empty()) CHECK_NEAR(r.progress.back().batch_eta_s, 0.0, 1e-9);

  // Again: the complete drives are skipped, the broken one fails again.
  Recorded again;
  const dps::BatchResult second = dps::RunBatch(drives, o, Record(&again));
  CHECK_EQ(second.skipped, 3);
  CHECK_EQ(second.processed, 0);
  CHECK_EQ(second.failed, 1);
  CHECK(again.progress.empty());

  // Shard 1 of 2 with --force: drives 1 and 3 (broken and c).
  o.force = true;
  o.shard = 1;
  o.shards = 2;
  Recorded shard;
  const dps::BatchResult third = dps::RunBatch(drives, o, Record(&shard));
  CHECK_EQ(third.processed, 1);
  CHECK_EQ(third.failed, 1);
  CHECK(shard.finished == std::vector<std::string>{"c"});
}

void TestShardsAndLists() {
  const std::vector<std::string> all = {"d0", "d1", "d2", "d3", "d4"};
  CHECK(dps::ShardOf(all, 0, 2) == (std::vector<std::string>{"d0", "d2", "d4"}));
  CHECK(dps::ShardOf(all, 2, 3) == (std::vector<std::string>{"d2"}));
  std::set<std::string> union_of_shards;
  for (int i = 0; i < 3; ++i) {
    for (const std::string& d : dps::ShardOf(all, i, 3)) CHECK(union_of_shards.insert(d).second);
  }
  CHECK_EQ(union_of_shards.size(), all.size());
  int shard = -1, shards = -1;
  dps::ParseShard("2/5", &shard, &shards);
  CHECK_EQ(shard, 2);
  CHECK_EQ(shards, 5);
  for (const char* bad : {"5/5", "-1/3", "1/0", "x", "1/2x"}) CHECK_THROWS_WITH(dps::ParseShard(bad, &shard, &shards), dps::Error, bad);
  const fs::path list = kTmp / "list.txt";
  std::ofstream(list) << "# drives\n/data/one\n\n/data/two\n";
  CHECK(dps::ReadDriveList(list.string()) == (std::vector<std::string>{"/data/one", "/data/two"}));
  CHECK_THROWS_WITH(dps::ReadDriveList((kTmp / "missing.txt").string()), dps::Error, "missing.txt");
  dps::BatchOptions o;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "out_root");
  o.out_root = "x";
  o.jobs = 0;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "jobs");
}

// Nothing a user recorded is ever replaced or deleted (issue: data loss): an output that is or lies
// inside the drive, the current folder, a folder dps did not write, two drives of one name.
void TestOutputsNeverDestroyInputs(const std::string& drive) {
  dps::DriveOptions o;
  o.map_video = false;
  const fs::path d(drive), parent = d.parent_path();
  const auto intact = [&] { return fs::exists(d / "rig.yaml") && fs::exists(d / "can.csv") && fs::exists(d / "left"); };
  // --out <the drive's parent>: the output would be the drive itself.
  CHECK_THROWS_WITH(dps::ProcessDrive(drive, parent.string(), o), dps::Error, "input");
  // --out <the drive>: the output would lie inside it.
  CHECK_THROWS_WITH(dps::ProcessDrive(drive, drive, o), dps::Error, "input");
  CHECK(intact());
  CHECK(!fs::exists(d / d.filename()));
  // "." from inside the drive names the drive, not ".", so ../results/<drive> is its output and the
  // other results stay.
  const fs::path here = fs::current_path();
  fs::create_directories(kTmp / "results" / "other");
  std::ofstream(kTmp / "results" / "other" / "keep.txt") << "mine\n";
  fs::current_path(d);
  const dps::DriveSummary s = dps::ProcessDrive(".", "../../results", o);
  fs::current_path(here);
  CHECK_EQ(s.drive, d.filename().string());
  CHECK(fs::exists(kTmp / "results" / "other" / "keep.txt"));
  CHECK(fs::exists(kTmp / "results" / d.filename() / "summary.json"));
  // A killed run's temporary folder (its process gone) is removed by the next run; a running
  // process's is kept.
  const fs::path stale = kTmp / "results" / ("." + d.filename().string() + ".tmp-2147483646");
  const fs::path live = kTmp / "results" / ("." + d.filename().string() + ".tmp-1");
  fs::create_directories(stale);
  fs::create_directories(live);
  dps::ProcessDrive(drive, (kTmp / "results").string(), o);
  CHECK(!fs::exists(stale));
  CHECK(fs::exists(live));  // pid 1 runs
  fs::remove_all(live);
  // A folder of that name that dps did not write is left alone, before any work.
  fs::create_directories(kTmp / "results2" / d.filename());
  std::ofstream(kTmp / "results2" / d.filename() / "notes.txt") << "mine\n";
  CHECK_THROWS_WITH(dps::ProcessDrive(drive, (kTmp / "results2").string(), o), dps::Error, "left alone");
  CHECK(fs::exists(kTmp / "results2" / d.filename() / "notes.txt"));
  // The current folder as the output.
  fs::current_path(kTmp / "results2");
  CHECK_THROWS_WITH(dps::CheckOutputFolder(".", {drive}), dps::Error, "current folder");
  fs::current_path(here);
  // dps-synth: never into the current folder, never over a folder it did not write.
  dps::SynthOptions so;
  so.frames = 1;
  so.overwrite = true;
  const dps::Scene scene = dps_test::SmallScene("lead_car", 320, 240);
  CHECK_THROWS_WITH(dps::Synthesize(scene, (kTmp / "results2" / d.filename()).string(), so), dps::Error, "left alone");
  fs::current_path(kTmp / "results2");
  CHECK_THROWS_WITH(dps::Synthesize(scene, ".", so), dps::Error, "current folder");
  fs::current_path(here);
  CHECK(fs::exists(kTmp / "results2" / d.filename() / "notes.txt"));
  // Two drives of one folder name in a batch: neither runs, both are reported, nothing written.
  fs::create_directories(kTmp / "twin");
  fs::copy(d, kTmp / "twin" / d.filename(), fs::copy_options::recursive);
  dps::BatchOptions b;
  b.out_root = (kTmp / "twins_out").string();
  b.jobs = 2;
  b.drive = o;
  Recorded r;
  const dps::BatchResult result = dps::RunBatch({drive, (kTmp / "twin" / d.filename()).string()}, b, Record(&r));
  CHECK_EQ(result.failed, 2);
  CHECK_EQ(result.processed, 0);
  CHECK(!fs::exists(kTmp / "twins_out" / d.filename()));
  CHECK(r.failed.size() == 2 && r.failed[0].find("two drives of one folder name") != std::string::npos);
}

}  // namespace

int main() {
  fs::remove_all(kTmp);
  fs::create_directories(kTmp);
  TestShardsAndLists();
  const std::vector<std::string> drives = MakeDrives();
  TestBatch(drives);
  TestOutputsNeverDestroyInputs(drives[0]);
  fs::remove_all(kTmp);
  return dps_test::Report();
}
