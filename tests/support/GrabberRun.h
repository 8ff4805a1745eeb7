/* mrpt_wifi — runs Debian's rawlog-grabber with libmrpt_wifi_sensor.so for tests. */
#pragma once

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CObservationWiFiScan.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "TestSupport.h"

namespace mrpt_wifi::test
{
/** A share/rawlog-grabber config with some keys set to test values, each in the line where the
 *  example has it (the others untouched; keys the file lacks are appended to its last section,
 *  the CSI sensor's). Returns `out`. */
inline std::string deriveGrabberIni(
    const std::string& shareIni, const std::map<std::string, std::string>& keys,
    const std::string& out)
{
    std::istringstream in(readFile(sourceDir() + "/share/rawlog-grabber/" + shareIni));
    std::ostringstream o;
    auto pending = keys;
    for (std::string line; std::getline(in, line);)
    {
        const auto eq = line.find('=');
        if (eq != std::string::npos && line[0] != ';' && line[0] != '#')
        {
            std::string key = line.substr(0, eq);
            key.erase(key.find_last_not_of(" \t") + 1);
            if (auto it = pending.find(key); it != pending.end())
            {
                o << key << " = " << it->second << "\n";
                pending.erase(it);
                continue;
            }
        }
        o << line << "\n";
    }
    for (const auto& [k, v] : pending) o << k << " = " << v << "\n";
    std::ofstream(out) << o.str();
    return out;
}

/** Every object of a (possibly gzipped) rawlog, in order; stops at its end. */
inline std::vector<mrpt::serialization::CSerializable::Ptr> readRawlog(const std::string& path)
{
    std::vector<mrpt::serialization::CSerializable::Ptr> out;
    mrpt::io::CFileGZInputStream f(path);
    auto arch = mrpt::serialization::archiveFrom(f);
    for (;;)
    {
        mrpt::serialization::CSerializable::Ptr obj;
        try
        {
            arch >> obj;
        }
        catch (const std::exception&)
        {
            break;  // end of file
        }
        out.push_back(obj);
    }
    return out;
}

struct GrabberRecording
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    std::vector<CObservationWiFiScan::Ptr> scans;
    std::string log;
    int exitCode = -1;
};

/** Runs rawlog-grabber in `dir` for `seconds`, stops it as a user does (a key on stdin), and
 *  reads back the CSI frames of the rawlog it wrote. */
inline GrabberRecording runGrabber(
    const TempDir& dir, const std::string& ini, double seconds, int timeoutSeconds = 120)
{
    GrabberRecording r;
    char cmd[1024];
    std::snprintf(
        cmd, sizeof(cmd),
        "cd %s && (sleep %.1f; echo) | timeout %d rawlog-grabber -p %s/libmrpt_wifi_sensor.so %s",
        dir.path().c_str(), seconds, timeoutSeconds, libDir().c_str(), ini.c_str());
    const auto res = run(cmd);
    r.exitCode = res.exitCode;
    r.log = res.output;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    {
        if (entry.path().extension() != ".rawlog") continue;
        for (const auto& obj : readRawlog(entry.path().string()))
        {
            if (auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(obj))
                r.frames.push_back(csi);
            else if (auto scan = std::dynamic_pointer_cast<CObservationWiFiScan>(obj))
                r.scans.push_back(scan);
        }
    }
    return r;
}

}  // namespace mrpt_wifi::test
