#include "apps/crowd_outputs.h"

#include <unistd.h>

#include <sys/wait.h>

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

namespace {

// POSIX shell single quotes: nothing inside is special except ' itself.
std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

Mp4Writer::Mp4Writer(const std::filesystem::path& ffmpeg, const std::filesystem::path& out, int width, int height,
                     float fps)
    : out_(out), frame_bytes_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4) {
  // A failed ffmpeg closes the pipe; without this the next write would kill strata with SIGPIPE instead of
  // returning an error that names the file.
  std::signal(SIGPIPE, SIG_IGN);
  std::ostringstream cmd;
  cmd << shell_quote(ffmpeg.string()) << " -hide_banner -loglevel error -nostdin -y -f rawvideo -pix_fmt rgba -s "
      << width << "x" << height << " -r " << fps << " -i - -vf " << shell_quote("crop=trunc(iw/2)*2:trunc(ih/2)*2")
      << " -pix_fmt yuv420p " << shell_quote(out.string());
  pipe_ = ::popen(cmd.str().c_str(), "w");
  if (!pipe_) throw std::runtime_error(out.string() + ": cannot start ffmpeg");
}

Mp4Writer::~Mp4Writer() {
  if (pipe_) {
    ::pclose(pipe_);
    std::error_code ec;
    std::filesystem::remove(out_, ec);  // never finished: not a usable video
  }
}

void Mp4Writer::write(const std::vector<std::uint8_t>& rgba) {
  if (rgba.size() != frame_bytes_)
    throw std::runtime_error(out_.string() + ": frame of " + std::to_string(rgba.size()) + " bytes, expected " +
                             std::to_string(frame_bytes_));
  if (std::fwrite(rgba.data(), 1, rgba.size(), pipe_) != rgba.size())
    throw std::runtime_error(out_.string() + ": ffmpeg stopped reading frames (see its message above)");
  ++frames_;
}

std::size_t Mp4Writer::finish() {
  FILE* pipe = pipe_;
  pipe_ = nullptr;
  const int status = ::pclose(pipe);
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::error_code ec;
    std::filesystem::remove(out_, ec);
    throw std::runtime_error(out_.string() + ": ffmpeg failed (exit status " +
                             std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  }
  return frames_;
}

}  // namespace strata::cli
