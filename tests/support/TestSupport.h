/* mrpt_wifi — shared helpers for the test suites. */
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace mrpt_wifi::test
{
/** The project's shared/ folder (real captures), empty if it isn't beside the checkout. */
inline std::string sharedDir()
{
    const std::string d = MRPT_WIFI_SHARED_DIR;
    return std::filesystem::is_directory(d) ? d : std::string();
}

/** Path of a real capture in shared/data/real, or empty if absent. */
inline std::string realCapture(const std::string& name)
{
    const std::string d = sharedDir();
    if (d.empty()) return {};
    const std::string p = d + "/data/real/" + name;
    return std::filesystem::exists(p) ? p : std::string();
}

#define MRPT_WIFI_REQUIRE_REAL_CAPTURE(var, name)                 \
    const std::string var = ::mrpt_wifi::test::realCapture(name); \
    if (var.empty()) GTEST_SKIP() << "real capture " << name << " not found (../shared absent)"

inline std::string binDir()
{
    return MRPT_WIFI_BIN_DIR;
}
inline std::string libDir()
{
    return MRPT_WIFI_LIB_DIR;
}
inline std::string sourceDir()
{
    return MRPT_WIFI_SOURCE_DIR;
}

/** A fresh temporary folder, removed with the object. */
class TempDir
{
public:
    TempDir()
    {
        std::string tmpl =
            (std::filesystem::temp_directory_path() / "mrpt_wifi_test_XXXXXX").string();
        path_ = mkdtemp(tmpl.data());
    }
    ~TempDir()
    {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

/** A fresh path (nothing created there yet) inside this test program's own temporary folder,
 *  which is removed when the program exits: `tempPath(".yaml")` →
 * `/tmp/mrpt_wifi_test_Ab12Cd/7.yaml`. Use it instead of mrpt::system::getTempFileName(), which
 * always creates an empty
 *  `/tmp/mrpt_temp*` file (ignoring TMPDIR) that nothing removes. */
inline std::string tempPath(const std::string& suffix = {})
{
    static const TempDir dir;
    static std::atomic<unsigned> counter{0};
    return dir.file(std::to_string(counter++) + suffix);
}

struct CommandResult
{
    int exitCode = -1;
    std::string output;  //!< stdout and stderr together
};

/** Runs a shell command, capturing stdout+stderr. */
inline CommandResult run(const std::string& command)
{
    CommandResult r;
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((command + " 2>&1").c_str(), "r"), &pclose);
    if (!pipe) return r;
    std::array<char, 4096> buf{};
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe.get())) > 0) r.output.append(buf.data(), n);
    const int status = pclose(pipe.release());
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

inline std::string readFile(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

/** What a command printed on stdout and on stderr, apart, and how it exited. */
struct SeparateOutputs
{
    int rc = -1;
    std::string out, err;
};

/** Runs a shell command, capturing stdout and stderr separately (through files in this
 *  program's temporary folder). */
inline SeparateOutputs runSeparately(const std::string& command)
{
    static std::atomic<unsigned> n{0};
    const std::string base = tempPath() + "_run" + std::to_string(n++);
    const int st = std::system((command + " >" + base + ".out 2>" + base + ".err").c_str());
    SeparateOutputs r;
    r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.out = readFile(base + ".out");
    r.err = readFile(base + ".err");
    return r;
}

}  // namespace mrpt_wifi::test
