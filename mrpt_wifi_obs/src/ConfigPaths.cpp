/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <dlfcn.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

namespace mrpt_wifi::config
{
namespace
{
namespace fs = std::filesystem;

/** The folder this library was loaded from, empty if the loader does not say. */
fs::path libraryDirectory()
{
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&libraryDirectory), &info) && info.dli_fname)
    {
        std::error_code ec;
        const auto p = fs::canonical(info.dli_fname, ec);
        if (!ec) return p.parent_path();
    }
    return {};
}

std::string readSmallFile(const fs::path& p, std::uintmax_t maxBytes)
{
    std::error_code ec;
    if (!fs::is_regular_file(p, ec) || fs::file_size(p, ec) > maxBytes || ec) return {};
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

bool sameSection(
    const mrpt::config::CConfigFileBase& a, const mrpt::config::CConfigFileBase& b,
    const std::string& section)
{
    std::vector<std::string> ka, kb;
    a.getAllKeys(section, ka);
    b.getAllKeys(section, kb);
    if (ka.size() != kb.size()) return false;
    for (const auto& k : ka)
        if (!b.keyExists(section, k) ||
            a.read_string(section, k, "") != b.read_string(section, k, ""))
            return false;
    return true;
}

bool sameContent(
    const mrpt::config::CConfigFileBase& a, const mrpt::config::CConfigFileBase& b,
    const std::string& section)
{
    if (!section.empty()) return sameSection(a, b, section);
    std::vector<std::string> sa, sb;
    a.getAllSections(sa);
    b.getAllSections(sb);
    if (std::set<std::string>(sa.begin(), sa.end()) != std::set<std::string>(sb.begin(), sb.end()))
        return false;
    return std::all_of(
        sa.begin(), sa.end(), [&](const std::string& s) { return sameSection(a, b, s); });
}

fs::path expandHome(const std::string& value)
{
    if (value == "~" || value.rfind("~/", 0) == 0)
        if (const char* home = std::getenv("HOME"); home && *home)
            return fs::path(home) / value.substr(value.size() > 1 ? 2 : 1);
    return fs::path(value);
}

bool pathExists(const fs::path& p)
{
    std::error_code ec;
    return fs::exists(p, ec);
}

/** `../arrays/x.yaml` -> `arrays/x.yaml`: the part a data folder may hold. */
fs::path withoutLeadingDots(const fs::path& p)
{
    fs::path out;
    bool leading = true;
    for (const auto& part : p)
    {
        if (leading && (part == ".." || part == ".")) continue;
        leading = false;
        out /= part;
    }
    return out;
}
}  // namespace

std::vector<std::string> dataDirectories()
{
    std::vector<std::string> dirs;
    const auto add = [&](const fs::path& d)
    {
        std::error_code ec;
        if (d.empty() || !fs::is_directory(d, ec)) return;
        const std::string s = fs::canonical(d, ec).string();
        if (!ec && std::find(dirs.begin(), dirs.end(), s) == dirs.end()) dirs.push_back(s);
    };
    if (const auto lib = libraryDirectory(); !lib.empty()) add(lib / MRPT_WIFI_DATADIR_FROM_LIBDIR);
    add(MRPT_WIFI_SOURCE_SHARE_DIR);
    add(MRPT_WIFI_INSTALL_SHARE_DIR);
    return dirs;
}

std::string findDataFile(const std::string& relative)
{
    const auto dirs = dataDirectories();
    for (const auto& d : dirs)
        if (pathExists(fs::path(d) / relative)) return (fs::path(d) / relative).string();
    std::string tried;
    for (const auto& d : dirs) tried += (tried.empty() ? "" : ", ") + d;
    throw std::invalid_argument(
        "cannot find '" + relative + "' in the mrpt_wifi data folder (looked in: " +
        (tried.empty() ? std::string("none exists; expected ") + MRPT_WIFI_INSTALL_SHARE_DIR
                       : tried) +
        ")");
}

std::string iniDirectory(const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
    std::error_code ec;
    if (const auto* file = dynamic_cast<const mrpt::config::CConfigFile*>(&cfg))
    {
        const std::string name = file->getAssociatedFile();
        if (name.empty()) return {};
        return fs::absolute(fs::path(name), ec).parent_path().string();
    }
    // rawlog-grabber, pf-localization: a copy of the file named among the program's arguments.
    const std::string cmdline = readSmallFile("/proc/self/cmdline", 1 << 20);
    std::vector<std::string> args;
    for (size_t start = 0; start < cmdline.size();)
    {
        const size_t end = std::min(cmdline.find('\0', start), cmdline.size());
        args.push_back(cmdline.substr(start, end - start));
        start = end + 1;
    }
    std::set<std::string> found;
    for (size_t i = 1; i < args.size(); ++i)
    {
        const fs::path p(args[i]);
        if (p.extension() == ".so") continue;
        const std::string content = readSmallFile(p, 4 << 20);
        if (content.empty()) continue;
        try
        {
            mrpt::config::CConfigFileMemory candidate;
            candidate.setContent(content);
            if (sameContent(cfg, candidate, section))
                found.insert(fs::absolute(p, ec).parent_path().string());
        }
        catch (const std::exception&)
        {
            // not an .ini
        }
    }
    return found.size() == 1 ? *found.begin() : std::string();
}

std::string iniDirectoryOf(const std::string& iniPath)
{
    std::error_code ec;
    return fs::absolute(fs::path(iniPath), ec).parent_path().lexically_normal().string();
}

ResolvedPath resolveConfigPath(
    const std::string& value, const std::string& iniDir, const std::string& dataKind,
    const std::string& what)
{
    if (value.empty()) return {};
    const fs::path given = expandHome(value);
    if (given.is_absolute())
    {
        if (!pathExists(given))
            throw std::invalid_argument(what + " = " + value + ": no such file or folder");
        return {given.string(), {}};
    }
    std::vector<std::string> tried;
    if (!iniDir.empty())
    {
        const fs::path p = fs::path(iniDir) / given;
        if (pathExists(p)) return {p.lexically_normal().string(), {}};
        tried.push_back(p.lexically_normal().string() + " (beside the .ini)");
    }
    if (pathExists(given))
    {
        std::error_code ec;
        const std::string abs = fs::absolute(given, ec).lexically_normal().string();
        return {
            abs, iniDir.empty()
                     ? what + " = " + value +
                           ": the .ini's folder is unknown (configuration not read from a "
                           "file): taken from the working directory, " +
                           abs
                     : what + " = " + value + ": not beside the .ini (" + iniDir +
                           "): taken from the working directory, " + abs};
    }
    tried.push_back(value + " (working directory)");
    const bool bareName = value.find('/') == std::string::npos;
    // An antenna array by name is the documented form: no note. Anything else taken from the
    // data folder is noted (a shipped example used in place of the user's own file, say).
    const bool arrayByName = bareName && dataKind == "arrays";
    const fs::path inData = withoutLeadingDots(given);
    for (const auto& d : dataDirectories())
    {
        std::vector<fs::path> candidates;
        if (bareName && !dataKind.empty())
        {
            candidates.push_back(fs::path(d) / dataKind / given);
            candidates.push_back(fs::path(d) / dataKind / (value + ".yaml"));
        }
        if (!inData.empty()) candidates.push_back(fs::path(d) / inData);
        for (const auto& c : candidates)
        {
            if (pathExists(c))
                return {
                    c.string(), arrayByName ? std::string()
                                            : what + " = " + value +
                                                  ": not beside the .ini nor in the working "
                                                  "directory: using the data folder's " +
                                                  c.string()};
            tried.push_back(c.string());
        }
    }
    std::string list;
    for (const auto& t : tried) list += (list.empty() ? "" : ", ") + t;
    throw std::invalid_argument(
        what + " = " + value + ": no such file or folder (looked for " + list + ")");
}

std::vector<std::string> resolveConfigPathList(
    const std::vector<std::string>& items, const std::string& iniDir, const std::string& dataKind,
    const std::string& what, std::vector<std::string>* notes)
{
    std::vector<std::string> out;
    for (const auto& item : items)
    {
        const auto eq = item.find('=');
        const std::string prefix = eq == std::string::npos ? "" : item.substr(0, eq + 1);
        const auto r = resolveConfigPath(
            eq == std::string::npos ? item : item.substr(eq + 1), iniDir, dataKind, what);
        if (notes && !r.note.empty()) notes->push_back(r.note);
        out.push_back(prefix + r.path);
    }
    return out;
}
}  // namespace mrpt_wifi::config
