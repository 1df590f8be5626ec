#include "dps/util/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "dps/util/error.h"

namespace dps {

std::string TemporaryPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path p(path);
  const std::string name = p.filename().string();
  const std::string tmp_name = Str(".", name, ".tmp-", ::getpid(), "-", counter++,
                                   p.extension().string());
  return (p.parent_path() / tmp_name).string();
}

void RenameReplacing(const std::string& from, const std::string& to) {
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(from.c_str());
    throw Error(Str(to, ": cannot rename temporary file into place: ", reason));
  }
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  AtomicOutputFile file(path);
  file.stream() << content;
  file.Commit();
}

AtomicOutputFile::AtomicOutputFile(const std::string& path)
    : path_(path), tmp_path_(TemporaryPathFor(path)) {
  out_.open(tmp_path_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!out_) throw Error(Str(path, ": cannot create file: ", std::strerror(errno)));
  out_.precision(9);
}

AtomicOutputFile::~AtomicOutputFile() {
  if (!committed_) {
    out_.close();
    std::remove(tmp_path_.c_str());
  }
}

void AtomicOutputFile::Commit() {
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok || out_.fail()) {
    std::remove(tmp_path_.c_str());
    committed_ = true;
    throw Error(Str(path_, ": write failed"));
  }
  committed_ = true;
  RenameReplacing(tmp_path_, path_);
}

}  // namespace dps
