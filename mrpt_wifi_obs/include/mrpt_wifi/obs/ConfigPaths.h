/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <string>
#include <vector>

/** Where the files an .ini names are found. One rule for every plugin and program:
 *
 *  1. `~/...` is the home folder; an absolute path is used as written.
 *  2. A relative path is taken from the folder of the .ini that names it (so a copied .ini
 *     keeps files copied beside it). When that folder is unknown (the configuration was not
 *     read from a file) the working directory is used instead, with a note.
 *  3. Not there: from the working directory (what older versions did first), with a note.
 *  4. Not there either: from the data folders (dataDirectories()). A bare name of a data file
 *     (`rt-ac86u` for an antenna array) is looked up as `<data>/<kind>/NAME[.yaml]`; a path such
 *     as `../arrays/rt-ac86u.yaml` (the shipped configs' own form) as `<data>/arrays/...`.
 *
 *  Found in the working directory or the data folder (but an array by name): a note for the
 *  log. Nothing found: an error naming the value and every place tried. */
namespace mrpt_wifi::config
{
/** The data folders, first match wins, existing ones only:
 *  - `<folder of libmrpt_wifi_obs.so>/<libdir-to-datadir>/mrpt_wifi`: the installed data folder
 *    `<prefix>/share/mrpt_wifi`, whatever `cmake --install --prefix` was used;
 *  - the source tree's `share/` (programs run from the build tree);
 *  - `<CMAKE_INSTALL_PREFIX>/share/mrpt_wifi` as configured. */
std::vector<std::string> dataDirectories();

/** A file of the data folders, e.g. "arrays/rt-ac86u.yaml"; throws naming the folders tried. */
std::string findDataFile(const std::string& relative);

/** The folder of the .ini file that `cfg` was read from, absolute; empty when unknown.
 *  `CConfigFile` knows its file. MRPT's rawlog-grabber and pf-localization hand their sensors
 *  and maps a `CConfigFileMemory` copy of the file named on their command line: the folder is
 *  then that of the command-line argument (/proc/self/cmdline) naming a file whose `section`
 *  holds the same keys and values as `cfg` (all sections when `section` is empty). */
std::string iniDirectory(const mrpt::config::CConfigFileBase& cfg, const std::string& section);

/** The absolute folder of the .ini file at `iniPath` (for programs that read it themselves). */
std::string iniDirectoryOf(const std::string& iniPath);

/** A path resolved by resolveConfigPath(). */
struct ResolvedPath
{
    std::string path;  //!< the file or folder found
    /** Not empty when it was found somewhere a user might not expect (the working directory;
     *  the data folder, except for an antenna array given by name): worth a line in the log. */
    std::string note;
};

/** Resolves `value`, a file or folder named by key `what` (e.g. "[WIFI_CSI] bearing_array") in
 *  an .ini whose folder is `iniDir` (iniDirectory(); empty: unknown), by the rules above.
 *  `dataKind`: the data folder's subfolder where bare names are looked up ("arrays"), or empty.
 *  An empty value stays empty. Throws std::invalid_argument naming `what`, the value and the
 *  places tried when nothing exists. */
ResolvedPath resolveConfigPath(
    const std::string& value, const std::string& iniDir, const std::string& dataKind,
    const std::string& what);

/** resolveConfigPath() for a list value, "FILE" and/or "MAC=FILE" items (bearing_tx_arrays):
 *  the file part of each item resolved, the rest kept. Notes are appended to `notes`. */
std::vector<std::string> resolveConfigPathList(
    const std::vector<std::string>& items, const std::string& iniDir, const std::string& dataKind,
    const std::string& what, std::vector<std::string>* notes = nullptr);
}  // namespace mrpt_wifi::config
