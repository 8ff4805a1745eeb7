/* mrpt_wifi — every program's --help is current: it exits 0, names no program by a stale
 * name (csi-pcap2rawlog only in csi-import's alias note), writes the plugin path in one form
 * (<build or prefix>/lib/libmrpt_wifi_X.so, X a library the build makes), and every share/ or
 * docs/ file it mentions exists in the source tree (issue 52). */
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "TestSupport.h"

namespace fs = std::filesystem;
using namespace mrpt_wifi;

namespace
{
/** The programs this build made (CMake passes those whose targets exist). */
std::vector<std::string> programs()
{
    std::vector<std::string> out;
    std::stringstream ss(MRPT_WIFI_HELP_PROGRAMS);
    for (std::string p; std::getline(ss, p, ',');)
        if (!p.empty()) out.push_back(p);
    return out;
}

/** TCLAP wraps text at spaces and indents: one space for any run of white space. */
std::string collapseSpaces(const std::string& s)
{
    std::string out;
    for (const char c : s)
    {
        const bool space = c == ' ' || c == '\n' || c == '\t' || c == '\r';
        if (space && (out.empty() || out.back() == ' ')) continue;
        out += space ? ' ' : c;
    }
    return out;
}

/** Does a mentioned path exist? `*` as a glob of one name, `<...>` a placeholder: then the
 *  folder before it must exist. */
bool mentionedPathExists(const fs::path& root, std::string path)
{
    while (!path.empty() && std::string(".,;:)'`").find(path.back()) != std::string::npos)
        path.pop_back();
    const auto placeholder = path.find_first_of("<*{");
    if (placeholder == std::string::npos) return fs::exists(root / path);
    const auto slash = path.rfind('/', placeholder);
    const fs::path dir = root / path.substr(0, slash == std::string::npos ? 0 : slash);
    if (!fs::is_directory(dir)) return false;
    if (path[placeholder] != '*') return true;
    // share/arrays/*.yaml: at least one file with that ending
    const std::string ending = path.substr(placeholder + 1);
    for (const auto& e : fs::directory_iterator(dir))
    {
        const std::string name = e.path().filename().string();
        if (name.size() >= ending.size() &&
            name.compare(name.size() - ending.size(), ending.size(), ending) == 0)
            return true;
    }
    return false;
}
}  // namespace

TEST(HelpTexts, EveryProgramsHelpIsCurrent)
{
    const auto progs = programs();
    // The programs a user runs (issue 52's list): all built by a default build.
    for (const char* required :
         {"csi-import", "csi-pcap2rawlog", "csi-export", "csi-bearings", "csi-router",
          "mrpt-wifi-askpass", "mrpt-wifi-record", "wifi-calibrate", "wifi-pf-localization",
          "wifi-localize", "wifi-graphslam", "wifi-iot-map", "wifi-sar", "wifi-bearings-synth"})
        EXPECT_NE(std::find(progs.begin(), progs.end(), required), progs.end()) << required;

    const fs::path source = test::sourceDir();
    const std::regex pathMention(R"((?:^|[\s(`'"])((?:share|docs)/[A-Za-z0-9_.*<>{}/,-]+))");
    const std::regex pluginMention(R"(libmrpt_wifi_([a-z_]+)\.so)");
    size_t pathsChecked = 0;
    for (const auto& program : progs)
    {
        SCOPED_TRACE(program);
        const auto r = test::run(test::binDir() + "/" + program + " --help");
        EXPECT_EQ(r.exitCode, 0) << r.output;
        ASSERT_GT(r.output.size(), 40u) << r.output;
        std::string text = collapseSpaces(r.output);

        // The old name of csi-import: only in its alias note and in the alias's own usage line.
        const std::string aliasNote = "csi-pcap2rawlog is the old name of csi-import";
        if (program == "csi-import" || program == "csi-pcap2rawlog")
        {
            EXPECT_NE(text.find(aliasNote), std::string::npos) << r.output;
        }
        for (size_t at; (at = text.find(aliasNote)) != std::string::npos;)
            text.erase(at, aliasNote.size());
        if (program == "csi-pcap2rawlog")
            text = std::regex_replace(text, std::regex(R"(\S*/csi-pcap2rawlog\b)"), "");
        EXPECT_EQ(text.find("csi-pcap2rawlog"), std::string::npos) << r.output;

        // The plugin path, one form: <build or prefix>/lib/libmrpt_wifi_X.so of a real library.
        const std::string pluginForm = "<build or prefix>/lib/";
        for (std::sregex_iterator it(text.begin(), text.end(), pluginMention), end; it != end; ++it)
        {
            const size_t at = size_t(it->position(0));
            EXPECT_TRUE(
                at >= pluginForm.size() &&
                text.compare(at - pluginForm.size(), pluginForm.size(), pluginForm) == 0)
                << "not written as " << pluginForm
                << "...: " << text.substr(at >= 30 ? at - 30 : 0, 30 + (*it)[0].length());
            EXPECT_TRUE(fs::exists(test::libDir() + "/libmrpt_wifi_" + (*it)[1].str() + ".so"))
                << (*it)[0].str();
        }

        // Files it points to exist (share/ as installed: the source tree's share/).
        for (std::sregex_iterator it(text.begin(), text.end(), pathMention), end; it != end;
             ++it, ++pathsChecked)
            EXPECT_TRUE(mentionedPathExists(source, (*it)[1].str())) << (*it)[1].str();
    }
    // The check above looked at something: the helps do point to share/ and docs/ files.
    EXPECT_GT(pathsChecked, 10u);
}

TEST(HelpTexts, TheCheckFindsAStalePathOrName)
{
    // The path check itself: a missing file, a missing folder before a placeholder, a glob
    // without a match are not accepted; present ones are.
    const fs::path source = test::sourceDir();
    EXPECT_TRUE(mentionedPathExists(source, "share/arrays/rt-ac86u.yaml"));
    EXPECT_TRUE(mentionedPathExists(source, "share/arrays/*.yaml"));
    EXPECT_TRUE(mentionedPathExists(source, "share/scenarios/README.md)."));
    EXPECT_FALSE(mentionedPathExists(source, "share/arrays/no-such-array.yaml"));
    EXPECT_FALSE(mentionedPathExists(source, "share/no-such-folder/<NAME>.yaml"));
    EXPECT_FALSE(mentionedPathExists(source, "share/arrays/*.no-such-ending"));
    EXPECT_EQ(collapseSpaces("a\n     b  c"), "a b c");
}
