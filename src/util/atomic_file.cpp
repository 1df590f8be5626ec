#include "dps/util/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
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

std::string AbsolutePath(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec);
  return (ec ? std::filesystem::absolute(path).lexically_normal() : p).string();
}

namespace {

// True when `inner` is `outer` or lies inside it (both absolute and normal).
bool Within(const std::filesystem::path& inner, const std::filesystem::path& outer) {
  auto i = inner.begin(), o = outer.begin();
  for (; o != outer.end() && !o->empty(); ++o, ++i) {
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

}  // namespace

void CheckOutputFolder(const std::string& output, const std::vector<std::string>& inputs) {
  const std::filesystem::path out(AbsolutePath(output));
  const std::filesystem::path here(AbsolutePath("."));
  if (Within(here, out)) {
    throw Error(Str(output, ": the output folder is or contains the current folder; choose another"));
  }
  for (const std::string& input : inputs) {
    const std::filesystem::path in(AbsolutePath(input));
    if (Within(in, out) || Within(out, in)) {
      throw Error(Str(output, ": the output folder would be, contain or lie inside the input ", input,
                      "; choose another"));
    }
  }
}

void CheckReplaceable(const std::string& target, const std::string& marker) {
  namespace fs = std::filesystem;
  if (!fs::exists(target)) return;
  if (!fs::is_directory(target) || !(fs::is_empty(target) || fs::exists(fs::path(target) / marker))) {
    throw Error(Str(target, ": exists and is not an output of this tool (no ", marker,
                    "); left alone: remove it yourself or choose another output"));
  }
}

void ReplaceFolder(const std::string& tmp, const std::string& target, const std::string& marker) {
  namespace fs = std::filesystem;
  try {
    CheckReplaceable(target, marker);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  if (fs::exists(target)) fs::remove_all(target);
  fs::rename(tmp, target);
}

std::string TemporaryFolderFor(const std::string& target) {
  namespace fs = std::filesystem;
  const fs::path t(AbsolutePath(target));
  const fs::path parent = t.parent_path();
  const std::string prefix = "." + t.filename().string() + ".tmp-";
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid_text = name.substr(prefix.size());
    if (pid_text.empty() || pid_text.find_first_not_of("0123456789") != std::string::npos) continue;
    const long pid = std::strtol(pid_text.c_str(), nullptr, 10);
    // A run still going (or another user's) keeps its folder.
    if (pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code remove_ec;
    fs::remove_all(it->path(), remove_ec);
  }
  return (parent / (prefix + std::to_string(::getpid()))).string();
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
