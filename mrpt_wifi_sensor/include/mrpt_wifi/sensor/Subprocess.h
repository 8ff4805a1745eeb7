/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <map>
#include <string>
#include <vector>

namespace mrpt_wifi
{
struct SubprocessResult
{
    int exitCode = -1;  //!< -1 if killed by a signal or not started
    std::string out, err;
    bool timedOut = false;
    double elapsed_s = 0;
};

/** Runs a program (no shell: argv[0] is looked up in PATH) with extra environment variables,
 * stdin from /dev/null, capturing stdout and stderr. After `timeout_s` the whole process group
 * gets SIGTERM, then SIGKILL: a call never hangs. Throws std::runtime_error if it can't start. */
SubprocessResult runSubprocess(
    const std::vector<std::string>& argv, double timeout_s,
    const std::map<std::string, std::string>& extraEnv = {});

}  // namespace mrpt_wifi
