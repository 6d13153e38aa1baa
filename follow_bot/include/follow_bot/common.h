// follow_bot builds on follow_bot_common's vocabulary (frames, the camera model, config fields,
// velocity limits, the nodelet base): its names are used unqualified in namespace follow_bot.
// Every follow_bot file that includes a follow_bot_common header includes this one too.
#pragma once

namespace follow_bot_common {}

namespace follow_bot {
using namespace follow_bot_common;  // NOLINT(google-build-using-namespace): one shared vocabulary
}  // namespace follow_bot
