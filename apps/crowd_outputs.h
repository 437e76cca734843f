#pragma once
// Outputs of `strata crowd` beside frames and profile: the paper's Table 1 for the rig's body levels, and an MP4
// of the rendered frames through an ffmpeg child process.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "scene/crowd.h"

namespace strata::cli {

// One row of the paper's Table 1 (vertices, triangles, vertices bound to one and to two joints, frames per second)
// for one body level of the crowd's rig, plus where the fps figure comes from.
struct Table1Row {
  int level = 0;
  std::size_t vertices = 0, triangles = 0, one_joint = 0, two_joints = 0, more_joints = 0;
  std::optional<double> fps;  // simulate + render + read-back of the whole crowd, per second; none if not measured
  std::size_t fps_frames = 0; // frames the fps was measured over
  std::string fps_source;     // "crowd run" (the level drawn) or "extra pass" (measured after it)
};

// Rows for every level of the scene's rig body (none without a body). The drawn level gets `drawn_fps` over
// `drawn_frames`; every other level is switched to and timed over `extra_frames` calls of `frame` (one untimed
// call first, so buffer uploads for the new level are not counted), then the drawn level is restored. With
// extra_frames = 0 the other levels get no fps. `frame` must simulate one frame and render it as the crowd run
// does, so the numbers compare.
std::vector<Table1Row> measure_table1(Crowd& scene, double drawn_fps, std::size_t drawn_frames,
                                      std::size_t extra_frames, const std::function<void()>& frame);
nlohmann::json table1_json(const std::vector<Table1Row>& rows);

// The first executable `name` on PATH, or empty.
std::filesystem::path find_on_path(const std::string& name);

// ---- The output directory a crowd run owns ----------------------------------------------------------------------
// Policy (docs/commands.md "Outputs of strata crowd"): a run owns its --out. A directory that does not exist is
// created; an empty one is used; one holding an earlier crowd output (summary.json with "command": "crowd") is
// emptied of exactly the files that output's manifest ("files") lists, and of the names a crowd run writes when
// the manifest is one a run left while running (killed); any other non-empty directory is refused, so a typo in
// --out cannot delete a user's files. Overwriting file by file (the old behaviour) was rejected: a shorter run
// left the longer run's later frames and video beside a summary that did not list them.
struct OutputClaim {
  std::string refused;             // non-empty: why the directory cannot be used
  std::size_t removed = 0;         // files of the earlier output removed
  std::size_t stale_temporaries = 0;  // temporary files of killed runs removed
};
OutputClaim claim_crowd_output_dir(const std::filesystem::path& dir);
// Removes ".NAME.PID.N.tmp" files (io/atomic_file.h) whose writer process no longer runs. Returns how many.
std::size_t remove_stale_temporaries(const std::filesystem::path& dir);

// Raw RGBA frames (top row first) piped into `ffmpeg -f rawvideo -pix_fmt rgba -s WxH -r FPS -i - ... out.mp4`
// (yuv420p, cropped to even dimensions, which yuv420p needs). ffmpeg's own messages go to its stderr at level
// "error" only. ffmpeg runs in a process group of its own, so a Ctrl-C at the terminal reaches strata alone,
// which then finishes the frame and closes the video properly (ffmpeg would otherwise stop on the same signal
// and leave a truncated file).
class Mp4Writer {
 public:
  // Starts ffmpeg; throws std::runtime_error when it cannot be started.
  Mp4Writer(const std::filesystem::path& ffmpeg, const std::filesystem::path& out, int width, int height, float fps);
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  // Throws std::runtime_error when ffmpeg stopped reading (it failed).
  void write(const std::vector<std::uint8_t>& rgba);
  // Waits for ffmpeg; throws std::runtime_error naming the file when it failed. Frames written so far.
  std::size_t finish();

 private:
  std::filesystem::path out_;
  std::size_t frame_bytes_ = 0;
  std::size_t frames_ = 0;
  int pipe_ = -1;   // write end of ffmpeg's stdin
  int pid_ = -1;    // the ffmpeg process
  int wait_child(); // its exit status, or -1
};

}  // namespace strata::cli
