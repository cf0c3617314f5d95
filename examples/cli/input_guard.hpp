#pragma once
// Inputs are never outputs: before any work a command hands its outputs and its inputs to
// check_outputs_not_inputs(), which refuses (io::Error naming the output and the input: one line,
// exit 2, nothing written) an output that
//   - is an input file: the same device and inode, so a hard or symbolic link to an input, or
//     a path through a linked folder, counts;
//   - lies inside an input folder (at any depth, links resolved), whether it exists or not.
// A folder input stands for itself and what it holds: a sequence folder's poses.txt, calib.txt
// and the files of clouds/ or velodyne/ (any sub-folder, one level down), a corrections folder's
// snapshots; a file linked in from elsewhere is an input too. Inputs that do not exist add
// nothing (their reader reports them).

#include <filesystem>
#include <map>
#include <string>
#include <system_error>
#include <vector>

#include <knnocc/io/error.hpp>
#include <knnocc/io/sequence.hpp>

#include "args.hpp"
#include "output_set.hpp"

#if defined(__unix__) || defined(__APPLE__)
#include <sys/stat.h>
#endif

namespace knnocc::cli {

namespace detail {

/// What names one file or folder whatever the path ("" when it cannot be read): device and inode
/// where the system has them, else the canonical path.
inline std::string file_identity(const std::filesystem::path& p, bool* is_folder = nullptr) {
#if defined(__unix__) || defined(__APPLE__)
  struct stat st;
  if (::stat(p.c_str(), &st) != 0 || !(S_ISREG(st.st_mode) || S_ISDIR(st.st_mode))) return {};
  if (is_folder) *is_folder = S_ISDIR(st.st_mode);
  return std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
#else
  std::error_code ec;
  const auto status = std::filesystem::status(p, ec);
  if (ec || !(std::filesystem::is_regular_file(status) || std::filesystem::is_directory(status)))
    return {};
  if (is_folder) *is_folder = std::filesystem::is_directory(status);
  return std::filesystem::canonical(p, ec).string();
#endif
}

/// The files and folders a command reads, by identity.
class InputSet {
 public:
  /// Adds `path` (given as `option`): a file, or a folder with what it holds.
  void add(const std::string& option, const std::string& path) {
    add_entry(option, path, io::is_sequence_dir(path) ? 2 : 1);
  }

  /// Throws io::Error for an output that is an input or lies inside an input folder.
  void refuse(const std::string& option, const std::string& output) const {
    namespace fs = std::filesystem;
    const auto file = files_.find(file_identity(output));
    if (file != files_.end())
      throw io::Error(
          output, option + " would replace an input (" + file->second + "); nothing was written");
    // The folder the output lands in (a symbolic link is replaced where it points), and every
    // folder above it.
    std::error_code ec;
    fs::path dir = fs::weakly_canonical(fs::absolute(output, ec), ec).parent_path();
    for (; !dir.empty(); dir = dir.parent_path()) {
      const auto folder = folders_.find(file_identity(dir));
      if (folder != folders_.end())
        throw io::Error(output, option + " lies inside an input folder (" + folder->second +
                                    "); nothing was written");
      if (dir == dir.root_path()) break;
    }
  }

 private:
  void add_entry(const std::string& option, const std::string& path, int depth) {
    bool folder = false;
    const std::string id = file_identity(path, &folder);
    if (id.empty()) return;
    (folder ? folders_ : files_).emplace(id, "'" + path + "' of " + option);
    if (!folder || depth == 0) return;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
      add_entry(option, it->path().string(), depth - 1);
  }

  // identity -> "'path' of --option"; never an empty identity.
  std::map<std::string, std::string> files_, folders_;
};

}  // namespace detail

/// The given options among `options` with their values: the inputs a command reads.
inline OutputList requested_inputs(const Args& args, const std::vector<std::string>& options) {
  return requested_outputs(args, options);
}

/// Refuses, before any work, an output that is one of the inputs or lies inside an input folder
/// (see the file comment); both lists are (option, path).
inline void check_outputs_not_inputs(const OutputList& outputs, const OutputList& inputs) {
  detail::InputSet set;
  for (const auto& [option, path] : inputs) set.add(option, path);
  for (const auto& [option, path] : outputs) set.refuse(option, path);
}

}  // namespace knnocc::cli
