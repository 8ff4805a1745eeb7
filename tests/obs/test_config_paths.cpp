// Files named in an .ini (mrpt_wifi/obs/ConfigPaths.h): from the .ini's own folder, then the
// working directory, then the data folder (arrays by name).
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "TestSupport.h"

using namespace mrpt_wifi;
namespace fs = std::filesystem;

namespace
{
/** Runs in `dir` for its lifetime (the working directory is process-wide: tests of this file
 *  restore it before they end). */
class InDirectory
{
public:
    explicit InDirectory(const fs::path& dir) : old_(fs::current_path()) { fs::current_path(dir); }
    ~InDirectory() { fs::current_path(old_); }

private:
    fs::path old_;
};

std::string canonical(const std::string& p)
{
    return fs::canonical(p).string();
}
}  // namespace

TEST(ConfigPaths, DataFolderOfTheBuildTreeIsTheSourceShare)
{
    const auto dirs = config::dataDirectories();
    ASSERT_FALSE(dirs.empty());
    // Not installed: the library runs from build/lib, so the source tree's share/ is found.
    EXPECT_NE(
        std::find(dirs.begin(), dirs.end(), canonical(test::sourceDir() + "/share")), dirs.end());
    EXPECT_EQ(
        canonical(config::findDataFile("arrays/rt-ac86u.yaml")),
        canonical(test::sourceDir() + "/share/arrays/rt-ac86u.yaml"));
    try
    {
        config::findDataFile("arrays/no-such-array.yaml");
        FAIL() << "a missing data file must throw";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("arrays/no-such-array.yaml"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("looked in"), std::string::npos) << e.what();
    }
}

TEST(ConfigPaths, RelativePathsComeFromTheIniFolderFirst)
{
    test::TempDir elsewhere, cwd;
    fs::create_directories(elsewhere.path() / "cfg");
    std::ofstream(elsewhere.file("cfg/aps.yaml")) << "transmitters: []\n";
    std::ofstream(cwd.file("aps.yaml")) << "transmitters: []\n";  // a decoy in the cwd
    std::ofstream(elsewhere.file("cfg/my.ini")) << "[S]\nfile = aps.yaml\n";
    mrpt::config::CConfigFile ini(elsewhere.file("cfg/my.ini"));
    const std::string iniDir = config::iniDirectory(ini, "S");
    EXPECT_EQ(canonical(iniDir), canonical(elsewhere.file("cfg")));
    EXPECT_EQ(config::iniDirectoryOf(elsewhere.file("cfg/my.ini")), iniDir);

    InDirectory in(cwd.path());
    const auto r = config::resolveConfigPath("aps.yaml", iniDir, "localization", "[S] file");
    EXPECT_EQ(canonical(r.path), canonical(elsewhere.file("cfg/aps.yaml")));
    EXPECT_TRUE(r.note.empty()) << r.note;

    // Not beside the .ini: the working directory, with a note saying so.
    std::ofstream(cwd.file("only-here.yaml")) << "x: 1\n";
    const auto w = config::resolveConfigPath("only-here.yaml", iniDir, "", "[S] file");
    EXPECT_EQ(canonical(w.path), canonical(cwd.file("only-here.yaml")));
    EXPECT_NE(w.note.find("working directory"), std::string::npos) << w.note;

    // The .ini's folder unknown: the working directory, with a note naming why.
    const auto u = config::resolveConfigPath("aps.yaml", "", "", "[S] file");
    EXPECT_EQ(canonical(u.path), canonical(cwd.file("aps.yaml")));
    EXPECT_NE(u.note.find("folder is unknown"), std::string::npos) << u.note;
}

TEST(ConfigPaths, ArraysByNameAndTheShippedRelativeFormFromACopiedIni)
{
    test::TempDir copy;
    const std::string iniDir = copy.path().string();
    // By name: found in the data folder, no note (it is the documented form).
    const auto byName = config::resolveConfigPath("rt-ac86u", iniDir, "arrays", "bearing_array");
    EXPECT_EQ(canonical(byName.path), canonical(test::sourceDir() + "/share/arrays/rt-ac86u.yaml"));
    EXPECT_TRUE(byName.note.empty()) << byName.note;
    EXPECT_EQ(
        canonical(config::resolveConfigPath("ap-linear-4.yaml", iniDir, "arrays", "x").path),
        canonical(test::sourceDir() + "/share/arrays/ap-linear-4.yaml"));
    // A shipped .ini copied elsewhere keeps working: ../arrays/... from the data folder.
    const auto shipped =
        config::resolveConfigPath("../arrays/rt-ac86u.yaml", iniDir, "arrays", "bearing_array");
    EXPECT_EQ(
        canonical(shipped.path), canonical(test::sourceDir() + "/share/arrays/rt-ac86u.yaml"));
    EXPECT_NE(shipped.note.find("data folder"), std::string::npos) << shipped.note;
    // Any other file taken from the data folder is noted: a shipped example used in place of
    // the user's own file must not go unseen.
    const auto example =
        config::resolveConfigPath("aps.example.yaml", iniDir, "localization", "transmitters_file");
    EXPECT_EQ(
        canonical(example.path),
        canonical(test::sourceDir() + "/share/localization/aps.example.yaml"));
    EXPECT_NE(example.note.find("data folder"), std::string::npos) << example.note;
    // A file beside the copy wins over the data folder's of the same name.
    std::ofstream(copy.file("rt-ac86u.yaml")) << "elements: [[0, 0]]\n";
    EXPECT_EQ(
        canonical(config::resolveConfigPath("rt-ac86u.yaml", iniDir, "arrays", "x").path),
        canonical(copy.file("rt-ac86u.yaml")));
    // Lists: FILE and MAC=FILE items, each file resolved.
    const auto list = config::resolveConfigPathList(
        {"ap-linear-4", "02:00:00:00:01:01=rt-ac86u.yaml"}, iniDir, "arrays", "bearing_tx_arrays");
    ASSERT_EQ(list.size(), 2u);
    EXPECT_EQ(canonical(list[0]), canonical(test::sourceDir() + "/share/arrays/ap-linear-4.yaml"));
    EXPECT_EQ(list[1], "02:00:00:00:01:01=" + (copy.path() / "rt-ac86u.yaml").string());
}

TEST(ConfigPaths, NothingFoundNamesTheKeyTheValueAndEveryPlaceTried)
{
    test::TempDir d;
    try
    {
        config::resolveConfigPath(
            "no-such-array", d.path().string(), "arrays", "[CSI] bearing_array");
        FAIL() << "a missing file must throw";
    }
    catch (const std::invalid_argument& e)
    {
        const std::string m = e.what();
        EXPECT_NE(m.find("[CSI] bearing_array = no-such-array"), std::string::npos) << m;
        EXPECT_NE(m.find(d.path().string()), std::string::npos) << m;            // beside the .ini
        EXPECT_NE(m.find("working directory"), std::string::npos) << m;          // the cwd
        EXPECT_NE(m.find("arrays/no-such-array.yaml"), std::string::npos) << m;  // data folder
    }
    EXPECT_THROW(
        config::resolveConfigPath("/no/such/file.yaml", "", "", "k"), std::invalid_argument);
    EXPECT_EQ(config::resolveConfigPath("", d.path().string(), "arrays", "k").path, "");
}

TEST(ConfigPaths, HomeIsExpanded)
{
    const char* home = std::getenv("HOME");
    if (!home || !fs::is_directory(home)) GTEST_SKIP() << "no HOME";
    EXPECT_EQ(
        fs::path(config::resolveConfigPath("~/", "/nonexistent", "", "k").path),
        fs::path(home) / "");
}

TEST(ConfigPaths, IniFolderOfAnInMemoryCopyComesFromTheCommandLine)
{
    // MRPT's rawlog-grabber hands sensors a CConfigFileMemory copy of the file named on its
    // command line. This test program's command line names no .ini: the folder is unknown.
    mrpt::config::CConfigFileMemory mem;
    mem.setContent(std::string("[S]\nfile = aps.yaml\n"));
    EXPECT_EQ(config::iniDirectory(mem, "S"), "");
    // (The positive case runs rawlog-grabber: tests/driver/test_hardware_configs.cpp.)
}
