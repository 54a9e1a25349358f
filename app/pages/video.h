// Image sequences to video with ffmpeg, when it is installed (it is optional: Debian `ffmpeg`).
// ffmpeg is started without a shell (posix_spawnp with an argument vector), so nothing in a file
// name is ever interpreted; its own glob matches the frames.
#pragma once

#include <string>

namespace dem::app {

/// Encodes DIR/PREFIX*.png (in name order) into `output` (H.264 MP4, even frame size) at `fps`.
/// Returns false with a message when ffmpeg is missing ("ffmpeg not found: install the Debian
/// package ffmpeg to get videos; the PNG frames are in DIR") or fails (its last error lines).
bool make_video(const std::string& directory, const std::string& prefix, const std::string& output, double fps,
                std::string* message);

}  // namespace dem::app
