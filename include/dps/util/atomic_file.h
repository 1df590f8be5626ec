// dps — files written so that a crash or a kill never leaves a half-written file under its final
// name (DESIGN.md §4): everything is written to a temporary name beside the target and renamed
// when complete.
#pragma once

#include <fstream>
#include <string>
#include <vector>

namespace dps {

// A temporary path beside `path` (same folder, so that the rename is atomic) that keeps the
// extension of `path`, so that writers that choose a format by extension (cv::imwrite,
// cv::VideoWriter) still work: "out/map.png" -> "out/.map.png.tmp-<pid>-<n>.png".
std::string TemporaryPathFor(const std::string& path);

// Renames `from` to `to`, replacing `to`; throws dps::Error naming both on failure.
void RenameReplacing(const std::string& from, const std::string& to);

// Writes `content` to `path` atomically; throws dps::Error naming the file on failure.
void WriteFileAtomically(const std::string& path, const std::string& content);

// `path` made absolute and normal (symbolic links resolved as far as the path exists), so that
// "d", "./d" and "../x/d" of one folder compare equal and "." has a name.
std::string AbsolutePath(const std::string& path);

// Output folders never destroy inputs: throws dps::Error naming both when `output` is, contains or
// lies inside one of `inputs`, or is or contains the current folder.
void CheckOutputFolder(const std::string& output, const std::vector<std::string>& inputs);

// Throws dps::Error naming `target` when it exists and is neither an empty folder nor one that holds
// `marker` (what ReplaceFolder would refuse to replace): to check before the work starts.
void CheckReplaceable(const std::string& target, const std::string& marker);

// Moves the complete folder `tmp` into place as `target`. An existing `target` is replaced only
// when it is empty or holds `marker` (a file the tool writes into every output folder of its
// own); otherwise `tmp` is removed and dps::Error says that `target` was left alone.
void ReplaceFolder(const std::string& tmp, const std::string& target, const std::string& marker);

// The temporary folder beside `target` that a process builds it in: "<parent>/.<name>.tmp-<pid>".
// Folders of that pattern left by processes that no longer run (killed runs) are removed first.
std::string TemporaryFolderFor(const std::string& target);

// A text output stream that becomes visible under its final name only on Commit(). Destroying an
// uncommitted file removes the temporary.
class AtomicOutputFile {
 public:
  // Opens a temporary file beside `path`; throws dps::Error when it cannot be created.
  explicit AtomicOutputFile(const std::string& path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream() { return out_; }
  // Flushes, closes and renames to the final path; throws dps::Error on any write failure.
  void Commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string tmp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace dps
