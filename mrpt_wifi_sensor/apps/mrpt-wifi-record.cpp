/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * mrpt-wifi-record: records the sensors of a rawlog-grabber .ini to a rawlog without a
 * terminal, for a service manager (share/systemd/mrpt-wifi-record.service). Debian's
 * rawlog-grabber (MRPT 2.5.8) cannot run unattended: it stops when stdin is readable
 * (mrpt::system::os::kbhit() polls fd 0, and stdin at end of file is readable), a signal kills
 * it without closing the gzip stream (the compressor's buffered tail is lost, the file ends
 * truncated), and on every stop it writes only half of the observations still queued, so the
 * newest one is never written. This program reads the same .ini, runs every sensor section in
 * its own thread as rawlog-grabber does, never reads stdin, and on SIGINT/SIGTERM/SIGHUP keeps
 * the sensors running for a short drain time (datagrams already in the socket buffer, frames
 * still being assembled), then writes everything received and closes the rawlog. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>
#include <mrpt/system/filesystem.h>
#include <mrpt/system/os.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

namespace
{
using Clock = std::chrono::steady_clock;

volatile sig_atomic_t g_stopSignal = 0;
void onStopSignal(int sig)
{
    g_stopSignal = sig;
}

/** One sensor section, its doProcess() called at its process_rate from its own thread. */
struct SensorThread
{
    std::string section;
    mrpt::hwdrivers::CGenericSensor::Ptr sensor;
    std::thread thread;
    std::mutex mtx;
    std::string error;  // what doProcess() threw, if it did
    std::atomic<bool> stop{false};

    /** Also when an error unwinds main: a joinable std::thread destroyed would terminate. */
    ~SensorThread()
    {
        stop = true;
        if (thread.joinable()) thread.join();
    }

    void start()
    {
        thread = std::thread(
            [this]
            {
                const auto period =
                    std::chrono::duration<double>(1.0 / std::max(1e-3, sensor->getProcessRate()));
                auto next = Clock::now();
                try
                {
                    while (!stop)
                    {
                        sensor->doProcess();
                        next += std::chrono::duration_cast<Clock::duration>(period);
                        if (next < Clock::now()) next = Clock::now();
                        std::this_thread::sleep_until(next);
                    }
                }
                catch (const std::exception& e)
                {
                    std::lock_guard<std::mutex> lk(mtx);
                    error = mrpt_wifi::cli::exceptionMessage(e);
                }
                catch (...)
                {
                    std::lock_guard<std::mutex> lk(mtx);
                    error = "unexpected exception (not a std::exception)";
                }
            });
    }
    std::string failure()
    {
        std::lock_guard<std::mutex> lk(mtx);
        return error;
    }
};

/** rawlog-grabber's file name: PREFIX_YYYY-MM-DD_HHhMMmSSs.rawlog (local time). */
std::string grabberStyleName(const std::string& prefix)
{
    mrpt::system::TTimeParts p;
    mrpt::system::timestampToParts(mrpt::Clock::now(), p, true);
    char buf[64];
    std::snprintf(
        buf, sizeof(buf), "_%04u-%02u-%02u_%02uh%02um%02us.rawlog", unsigned(p.year),
        unsigned(p.month), unsigned(p.day), unsigned(p.hour), unsigned(p.minute),
        unsigned(p.second));
    return prefix + buf;
}
}  // namespace

int main(int argc, char** argv)
{
    return mrpt_wifi::cli::runMain(
        "mrpt-wifi-record",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Records the sensors of a rawlog-grabber .ini to a rawlog, unattended: never "
                "reads stdin (no terminal needed), stops on SIGINT, SIGTERM or SIGHUP (or after "
                "--duration), then writes every observation received and closes the rawlog "
                "cleanly. For a service manager: share/systemd/mrpt-wifi-record.service. The "
                "CWiFiCSISensor and CWiFiOdometryUdpSensor drivers are built in; MRPT's own "
                "drivers too. Exit status: 0 stopped by a signal or --duration, everything "
                "written; 1 bad command line or .ini, a sensor failed to start, or a sensor "
                "failed while recording (the rawlog then holds everything received until "
                "then, closed cleanly). See docs/troubleshooting.md.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIni(
                "config", "rawlog-grabber .ini ([global] and one section per sensor)", true, "",
                "CONFIG.ini", cmd);
            TCLAP::MultiArg<std::string> argPlugin(
                "p", "plugin", "More sensor plugin module(s) to load, as rawlog-grabber -p", false,
                "LIB.so", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "rawlog",
                "Output rawlog (default: [global] rawlog_prefix + _DATE_TIME.rawlog in the "
                "working directory, as rawlog-grabber names it)",
                false, "", "OUT.rawlog", cmd);
            TCLAP::ValueArg<double> argDuration(
                "d", "duration", "Stop after this many seconds (0: only on a signal)", false, 0,
                "S", cmd);
            TCLAP::ValueArg<double> argDrain(
                "", "drain-time",
                "After the stop signal, keep the sensors running this long so that datagrams "
                "already queued and frames still being assembled are recorded",
                false, 0.5, "S", cmd);
            if (const int rc =
                    mrpt_wifi::cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            // A use of the sensor library, so that the linker keeps it (its initializer
            // registers the drivers): `driver = CWiFiCSISensor` then works without -p.
            if (!mrpt_wifi::CWiFiCSISensor::classCWiFiCSISensor.ptrCreateObject)
                throw std::logic_error("libmrpt_wifi_sensor is not linked");
            for (const auto& p : argPlugin.getValue())
            {
                // This program links libmrpt_wifi_sensor already: loading a second copy would
                // register its classes twice.
                if (mrpt::system::extractFileName(p).rfind("libmrpt_wifi_sensor", 0) == 0)
                {
                    std::cerr << "mrpt-wifi-record: note: " << p
                              << " is built in, not loaded again\n";
                    continue;
                }
                mrpt_wifi::cli::loadPlugin(p);
            }
            const std::string iniPath = argIni.getValue();
            if (!mrpt::system::fileExists(iniPath))
                throw std::runtime_error("cannot read '" + iniPath + "'");
            mrpt::config::CConfigFile ini(iniPath);
            if (ini.read_bool("global", "use_sensoryframes", false))
                throw std::invalid_argument(
                    iniPath +
                    ": [global] use_sensoryframes = true is not supported (mrpt-wifi-record "
                    "writes observations, as rawlog-grabber with use_sensoryframes = false); set "
                    "it to false");
            const int gzLevel = ini.read_int("global", "rawlog_GZ_compress_level", 1);
            const int writePeriod_ms =
                std::clamp(ini.read_int("global", "GRABBER_PERIOD_MS", 1000), 10, 5000);
            const int launchGap_ms =
                std::clamp(ini.read_int("global", "time_between_launches", 300), 0, 10000);

            // ---- sensors: every section but [global] (rawlog-grabber-ignore skips one)
            std::vector<std::unique_ptr<SensorThread>> sensors;
            std::vector<std::string> sections;
            ini.getAllSections(sections);
            for (const auto& sec : sections)
            {
                if (sec == "global" || sec.empty() ||
                    ini.read_bool(sec, "rawlog-grabber-ignore", false))
                    continue;
                const std::string driver = ini.read_string(sec, "driver", "");
                if (driver.empty())
                    throw std::invalid_argument(
                        iniPath + ": section [" + sec +
                        "] has no `driver`: every section but [global] is a sensor, as for "
                        "rawlog-grabber (add `rawlog-grabber-ignore = true` to keep other "
                        "settings there)");
                auto s = std::make_unique<SensorThread>();
                s->section = sec;
                s->sensor = mrpt::hwdrivers::CGenericSensor::createSensorPtr(driver);
                if (!s->sensor)
                    throw std::invalid_argument(
                        iniPath + ": [" + sec + "] driver = " + driver +
                        ": no such sensor class (a plugin to load with -p?)");
                s->sensor->loadConfig(ini, sec);
                if (!(s->sensor->getProcessRate() > 0))
                    throw std::invalid_argument(
                        iniPath + ": [" + sec + "] process_rate must be > 0 (Hz)");
                sensors.push_back(std::move(s));
            }
            if (sensors.empty()) throw std::invalid_argument(iniPath + ": no sensor section");

            // Before any sensor thread exists: a stop signal only sets a flag, whichever thread
            // receives it, and the main loop sees it within 20 ms.
            struct sigaction sa = {};
            sa.sa_handler = onStopSignal;
            sigemptyset(&sa.sa_mask);
            for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
            ::signal(SIGPIPE, SIG_IGN);

            for (auto& s : sensors)
            {
                s->sensor->initialize();
                s->start();
                std::cerr << "mrpt-wifi-record: [" << s->section << "] started at "
                          << s->sensor->getProcessRate() << " Hz\n";
                if (launchGap_ms > 0 && &s != &sensors.back())
                    std::this_thread::sleep_for(std::chrono::milliseconds(launchGap_ms));
            }
            // Opened once every sensor has started (a sensor that cannot start leaves no empty
            // rawlog behind); what they gathered meanwhile waits in their queues.
            const std::string outPath =
                argOut.isSet()
                    ? argOut.getValue()
                    : grabberStyleName(ini.read_string("global", "rawlog_prefix", "dataset"));
            mrpt::io::CFileGZOutputStream out;
            if (!out.open(outPath, gzLevel))
                throw std::runtime_error("cannot write '" + outPath + "'");
            auto arch = mrpt::serialization::archiveFrom(out);

            std::cerr << "mrpt-wifi-record: recording to " << outPath
                      << " (stop with SIGINT/SIGTERM, e.g. Ctrl+C or systemctl stop)\n";

            std::map<std::string, uint64_t> perLabel;
            uint64_t written = 0;
            const auto writeAll = [&]
            {
                mrpt::hwdrivers::CGenericSensor::TListObservations all;  // time-ordered
                for (auto& s : sensors)
                {
                    mrpt::hwdrivers::CGenericSensor::TListObservations l;
                    s->sensor->getObservations(l);
                    all.insert(l.begin(), l.end());
                }
                for (const auto& [t, o] : all)
                {
                    arch << *o;
                    ++written;
                    const auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o);
                    ++perLabel
                        [obs ? obs->sensorLabel : std::string(o->GetRuntimeClass()->className)];
                }
            };

            const auto start = Clock::now();
            auto lastWrite = start;
            std::string stopReason, failure;
            while (stopReason.empty())
            {
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
                if (g_stopSignal)
                    stopReason = std::string("signal ") + ::strsignal(g_stopSignal);
                else if (
                    argDuration.getValue() > 0 &&
                    Clock::now() - start >= std::chrono::duration<double>(argDuration.getValue()))
                    stopReason = "duration reached";
                for (auto& s : sensors)
                    if (const auto e = s->failure(); !e.empty() && failure.empty())
                    {
                        failure = "[" + s->section + "] " + e;
                        stopReason = "sensor failed";
                    }
                if (Clock::now() - lastWrite >= std::chrono::milliseconds(writePeriod_ms))
                {
                    writeAll();
                    lastWrite = Clock::now();
                }
            }
            if (failure.empty() && argDrain.getValue() > 0)
                std::this_thread::sleep_for(std::chrono::duration<double>(argDrain.getValue()));
            for (auto& s : sensors) s->stop = true;
            for (auto& s : sensors)
                if (s->thread.joinable()) s->thread.join();
            writeAll();  // what the sensors appended in their last doProcess()
            out.close();
            sensors.clear();  // drivers release their devices (sockets, router sessions)

            std::cerr << "mrpt-wifi-record: stopped (" << stopReason << "): " << written
                      << " objects written to " << outPath;
            for (const auto& [label, n] : perLabel) std::cerr << ", " << label << " " << n;
            std::cerr << "\n";
            if (!failure.empty())
                throw std::runtime_error(
                    "sensor " + failure + " (the rawlog holds everything received until then)");
            return 0;
        });
}
