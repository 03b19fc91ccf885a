#pragma once
// The exit codes of the `fullarm` program (docs/cli.md).

namespace fullarm::app {

inline constexpr int kExitPass = 0;  ///< success, and the verdict (if any) passed
inline constexpr int kExitFail = 1;  ///< a failing verdict (the output folder is written)
inline constexpr int kExitBadInput =
    2;  ///< bad input: command line, configuration, scene, mesh; or an output that cannot be written
inline constexpr int kExitInternal = 3;      ///< an internal error (a defect of fullarm: please report it)
inline constexpr int kExitInconclusive = 4;  ///< a budget ran out before a verdict (the output folder is written)

}  // namespace fullarm::app
