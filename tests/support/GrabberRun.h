/* mrpt_wifi — runs Debian's rawlog-grabber with libmrpt_wifi_sensor.so for tests. */
#pragma once

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CObservationWiFiScan.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
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

/** The frames of a file the emulator wrote with --record-sent, decoded offline. */
inline std::vector<CObservationWiFiCSI::Ptr> decodeSentFrames(
    const std::string& file, uint16_t udpPort)
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiDecodeOptions o;
    o.udpPort = udpPort;
    decodeCsiFile(file, "auto", o, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
    return frames;
}

/** The last "kernel drops N" of the sensor's status lines in a grabber log (0 if none). */
inline size_t lastReportedKernelDrops(const std::string& log)
{
    const std::string key = "kernel drops ";
    const size_t p = log.rfind(key);
    return p == std::string::npos ? 0 : size_t(std::stoul(log.substr(p + key.size())));
}

/** How a recording compares with what the emulator sent (`--record-sent`): frames are matched
 *  by transmitter and sequence number (the recording may interleave the transmitters in another
 *  order than they were sent). A wall-clock run records however much the machine's load lets
 *  it: what counts is that nothing the emulator sent up to the last recorded frame went
 *  missing, not how many frames that was. */
struct SentVsRecorded
{
    size_t firstRecorded = 0;  //!< index among the sent frames of the earliest-sent recorded one
    size_t sentInSpan = 0;     //!< sent frames from the earliest-sent to the latest-sent recorded
    size_t missing = 0;        //!< of those, not recorded
    size_t neverSent = 0;      //!< recorded frames matching no sent frame
};
inline SentVsRecorded compareWithSent(
    const std::vector<CObservationWiFiCSI::Ptr>& recorded,
    const std::vector<CObservationWiFiCSI::Ptr>& sent)
{
    // Sequence numbers wrap at 4096: a key may repeat in a long run, each recorded frame takes
    // the earliest sent one of its key not taken yet.
    std::map<std::pair<std::string, uint16_t>, std::vector<size_t>> sentAt;
    for (size_t i = sent.size(); i-- > 0;)
        sentAt[{sent[i]->transmitter.asString(), sent[i]->sequenceNumber}].push_back(i);
    SentVsRecorded c;
    size_t matched = 0, first = sent.size(), last = 0;
    for (const auto& f : recorded)
    {
        auto it = sentAt.find({f->transmitter.asString(), f->sequenceNumber});
        if (it == sentAt.end() || it->second.empty())
        {
            ++c.neverSent;
            continue;
        }
        first = std::min(first, it->second.back());
        last = std::max(last, it->second.back());
        it->second.pop_back();
        ++matched;
    }
    if (matched == 0) return c;
    c.firstRecorded = first;
    c.sentInSpan = last - first + 1;
    c.missing = c.sentInSpan - matched;
    return c;
}

/** The emulator's summary.json (written when it stops), waiting for it at most `s` seconds. */
inline std::string emulatorSummaryJson(const std::string& stateDir, double s)
{
    const std::string path = stateDir + "/summary.json";
    for (int i = 0; i < int(s * 20) && !std::filesystem::exists(path); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return readFile(path);
}

}  // namespace mrpt_wifi::test
