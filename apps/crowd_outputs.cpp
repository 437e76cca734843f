#include "apps/crowd_outputs.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "rig/binding.h"
#include "scene/body_settings.h"

namespace strata::cli {

std::vector<Table1Row> measure_table1(Crowd& scene, double drawn_fps, std::size_t drawn_frames,
                                      std::size_t extra_frames, const std::function<void()>& frame) {
  std::vector<Table1Row> rows;
  const Body* body = scene.rig().body.get();
  if (!body) return rows;
  const DetailLevel drawn = scene.skin.level;
  for (std::size_t l = 0; l < body->levels.size(); ++l) {
    const BodyLevel& level = body->levels[l];
    const BindingStats stats = binding_stats(level.binding);
    Table1Row row;
    row.level = static_cast<int>(l);
    row.vertices = level.mesh.vertex_count();
    row.triangles = level.mesh.triangle_count();
    row.one_joint = stats.one_joint;
    row.two_joints = stats.two_joints;
    row.more_joints = stats.more_joints;
    if (DetailLevel::mesh(row.level) == drawn) {
      row.fps = drawn_fps;
      row.fps_frames = drawn_frames;
      row.fps_source = "crowd run";
    } else if (extra_frames > 0) {
      // The crowd goes on walking at the other level: the same walkers, camera and renderer, so the only change
      // is the mesh resolution. Restarting the scene instead would time a different stretch of the walk.
      set_detail_level(scene, DetailLevel::mesh(row.level));
      frame();  // untimed: the renderer uploads the new level's index buffer on its first frame
      const auto start = std::chrono::steady_clock::now();
      for (std::size_t f = 0; f < extra_frames; ++f) frame();
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      row.fps = seconds > 0 ? static_cast<double>(extra_frames) / seconds : 0.0;
      row.fps_frames = extra_frames;
      row.fps_source = "extra pass";
    }
    rows.push_back(row);
  }
  if (scene.skin.level != drawn) set_detail_level(scene, drawn);
  return rows;
}

nlohmann::json table1_json(const std::vector<Table1Row>& rows) {
  nlohmann::json table = nlohmann::json::array();
  for (const Table1Row& r : rows)
    table.push_back({{"level", r.level},
                     {"vertices", r.vertices},
                     {"triangles", r.triangles},
                     {"vertices_one_joint", r.one_joint},
                     {"vertices_two_joints", r.two_joints},
                     {"vertices_more_joints", r.more_joints},
                     {"fps", r.fps ? nlohmann::json(*r.fps) : nlohmann::json(nullptr)},
                     {"fps_frames", r.fps_frames},
                     {"fps_source", r.fps_source.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.fps_source)}});
  return table;
}

std::filesystem::path find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return {};
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::filesystem::path candidate = std::filesystem::path(dir) / name;
    if (::access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate)) return candidate;
  }
  return {};
}

OutputClaim claim_crowd_output_dir(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  OutputClaim claim;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return claim;
  if (!fs::is_directory(dir, ec)) {
    claim.refused = "--out: " + dir.string() + " is not a directory";
    return claim;
  }
  claim.stale_temporaries = remove_stale_temporaries(dir);
  if (fs::is_empty(dir, ec)) return claim;
  const fs::path summary = dir / "summary.json";
  nlohmann::json manifest;
  {
    std::ifstream in(summary);
    manifest = nlohmann::json::parse(in, nullptr, false);
  }
  if (!manifest.is_object() || manifest.value("command", "") != "crowd") {
    claim.refused = "--out: " + dir.string() +
                    " is not empty and holds no earlier strata crowd output (summary.json); give a new or empty "
                    "directory";
    return claim;
  }
  // Only names a crowd run can write: a manifest edited by hand cannot make a run delete anything else.
  auto ours = [](const std::string& name) {
    if (name == "crowd.mp4" || name == "profile.json" || name == "profile.csv" || name == "summary.json") return true;
    if (name.rfind("frame_", 0) != 0 || name.size() < 11 || name.substr(name.size() - 4) != ".png") return false;
    const std::string digits = name.substr(6, name.size() - 10);
    return !digits.empty() && std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  std::vector<std::string> names;
  if (manifest.contains("files") && manifest["files"].is_array() && !manifest.value("running", false)) {
    for (const nlohmann::json& f : manifest["files"])
      if (f.is_string()) names.push_back(f.get<std::string>());
  } else {
    // A run that was killed (its manifest still says running) or one from before manifests: what it may have
    // written is known only by name.
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) names.push_back(e.path().filename().string());
  }
  for (const std::string& name : names) {
    if (!ours(name) || name == "summary.json") continue;
    if (fs::remove(dir / name, ec)) ++claim.removed;
  }
  if (fs::remove(summary, ec)) ++claim.removed;  // last: until now it says what the directory holds
  return claim;
}

std::size_t remove_stale_temporaries(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::size_t removed = 0;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    // ".<target>.<pid>.<n>.tmp", the name AtomicFile picks.
    const std::string name = e.path().filename().string();
    if (name.size() < 8 || name[0] != '.' || name.substr(name.size() - 4) != ".tmp") continue;
    const std::string stem = name.substr(0, name.size() - 4);
    const std::size_t n_dot = stem.rfind('.');
    if (n_dot == std::string::npos || n_dot == 0) continue;
    const std::size_t pid_dot = stem.rfind('.', n_dot - 1);
    if (pid_dot == std::string::npos || pid_dot == 0) continue;
    const std::string pid_text = stem.substr(pid_dot + 1, n_dot - pid_dot - 1);
    if (pid_text.empty() || !std::all_of(pid_text.begin(), pid_text.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const long pid = std::strtol(pid_text.c_str(), nullptr, 10);
    // A live writer (another run in the same directory) keeps its file; ESRCH means no such process.
    if (pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)) continue;
    if (fs::remove(e.path(), ec)) ++removed;
  }
  return removed;
}

Mp4Writer::Mp4Writer(const std::filesystem::path& ffmpeg, const std::filesystem::path& out, int width, int height,
                     float fps)
    : out_(out), frame_bytes_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4) {
  // A failed ffmpeg closes the pipe; without this the next write would kill strata with SIGPIPE instead of
  // returning an error that names the file.
  std::signal(SIGPIPE, SIG_IGN);
  std::ostringstream rate;
  rate << fps;
  const std::vector<std::string> args = {ffmpeg.string(), "-hide_banner", "-loglevel", "error", "-nostdin", "-y",
                                         "-f", "rawvideo", "-pix_fmt", "rgba", "-s",
                                         std::to_string(width) + "x" + std::to_string(height), "-r", rate.str(),
                                         "-i", "-", "-vf", "crop=trunc(iw/2)*2:trunc(ih/2)*2", "-pix_fmt", "yuv420p",
                                         out.string()};
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(out.string() + ": cannot start ffmpeg (pipe)");
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attr;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  posix_spawnattr_init(&attr);
  // Its own process group (popen's shell was in ours): a terminal's SIGINT goes to strata only.
  posix_spawnattr_setpgroup(&attr, 0);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, ffmpeg.c_str(), &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    throw std::runtime_error(out.string() + ": cannot start ffmpeg: " + std::strerror(rc));
  }
  pid_ = pid;
  pipe_ = fds[1];
}

int Mp4Writer::wait_child() {
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return status;
}

Mp4Writer::~Mp4Writer() {
  if (pipe_ >= 0) {
    ::close(pipe_);
    wait_child();
    std::error_code ec;
    std::filesystem::remove(out_, ec);  // never finished: not a usable video
  }
}

void Mp4Writer::write(const std::vector<std::uint8_t>& rgba) {
  if (rgba.size() != frame_bytes_)
    throw std::runtime_error(out_.string() + ": frame of " + std::to_string(rgba.size()) + " bytes, expected " +
                             std::to_string(frame_bytes_));
  std::size_t done = 0;
  while (done < rgba.size()) {
    const ssize_t n = ::write(pipe_, rgba.data() + done, rgba.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(out_.string() + ": ffmpeg stopped reading frames (see its message above)");
    done += static_cast<std::size_t>(n);
  }
  ++frames_;
}

std::size_t Mp4Writer::finish() {
  ::close(pipe_);
  pipe_ = -1;
  const int status = wait_child();
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::error_code ec;
    std::filesystem::remove(out_, ec);
    throw std::runtime_error(out_.string() + ": ffmpeg failed (exit status " +
                             std::to_string(status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  }
  return frames_;
}

}  // namespace strata::cli
