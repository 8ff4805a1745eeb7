/* mrpt_wifi — measures live bearings against the target: the RT-AC86U emulator streams a
 * scenario (default: share/scenarios/kidnapped.yaml, 4 APs × 100 frames/s, 4×4, 80 MHz) to a
 * CWiFiCSISensor with bearing_algorithm set, run in-process as rawlog-grabber would (doProcess
 * at process_rate). Reports the frames that got a bearing, the skipped ones and the latency
 * from a frame's completion to its bearing (p50/p99/max). Target: ≥ 99 % with a bearing,
 * p99 ≤ 20 ms. Exit code 0 whether or not the target is met (it is a measurement). */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <thread>

#include "EmulatorProcess.h"

using namespace mrpt_wifi;

namespace
{
double cpuSeconds()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
}  // namespace

int main(int argc, char** argv)
{
    try
    {
        TCLAP::CmdLine cmd(
            "Measures live bearings (CWiFiCSISensor bearing_* keys) on the RT-AC86U emulator: "
            "share of frames with a bearing, skipped frames, latency frame → bearing.",
            ' ', "0.1");
        TCLAP::ValueArg<std::string> argAlgo(
            "a", "algo", "bearing_algorithm", false, "aoa_only", "NAME", cmd);
        TCLAP::ValueArg<std::string> argScenario(
            "", "scenario", "Emulator scenario", false,
            mrpt_wifi::test::sourceDir() + "/share/scenarios/kidnapped.yaml", "FILE.yaml", cmd);
        TCLAP::ValueArg<std::string> argChannel(
            "", "channel", "Channel the emulator streams (as --preconfigured)", false, "155/80",
            "CH/BW", cmd);
        TCLAP::ValueArg<double> argDuration(
            "d", "duration", "Seconds measured (after 1 s warm-up)", false, 20, "S", cmd);
        TCLAP::ValueArg<unsigned> argQueue(
            "", "queue", "bearing_queue_length", false, 64, "N", cmd);
        TCLAP::ValueArg<double> argRate(
            "", "process-rate", "doProcess calls per second", false, 200, "HZ", cmd);
        TCLAP::ValueArg<unsigned> argPort("p", "port", "UDP port", false, 25731, "PORT", cmd);
        cmd.parse(argc, argv);

        const double duration = argDuration.getValue();
        const uint16_t port = uint16_t(argPort.getValue());
        mrpt::config::CConfigFileMemory ini(
            "[CSI]\ndriver = CWiFiCSISensor\nsensorLabel = CSI\nprocess_rate = " +
            std::to_string(argRate.getValue()) +
            "\nsource = udp\nudp_bind_address = 127.0.0.1\nudp_port = " + std::to_string(port) +
            "\nstatus_period = 0\nbearing_algorithm = " + argAlgo.getValue() +
            "\nbearing_queue_length = " + std::to_string(argQueue.getValue()) + "\n");
        CWiFiCSISensor sensor;
        sensor.setMinLoggingLevel(mrpt::system::LVL_WARN);
        sensor.loadConfig(ini, "CSI");
        sensor.initialize();

        mrpt_wifi::test::EmulatorProcess emulator(
            {"--scenario", argScenario.getValue(), "--preconfigured", argChannel.getValue(),
             "--quiet"},
            port, duration + 5);

        const auto period = std::chrono::duration<double>(1.0 / argRate.getValue());
        uint64_t frames = 0, bearings = 0, warmupFrames = 0, warmupBearings = 0;
        const auto collect = [&]
        {
            mrpt::hwdrivers::CGenericSensor::TListObservations obs;
            sensor.getObservations(obs);
            for (const auto& [t, o] : obs)
            {
                if (std::dynamic_pointer_cast<CObservationWiFiCSI>(o)) ++frames;
                if (std::dynamic_pointer_cast<CObservationWiFiBearing>(o)) ++bearings;
            }
        };
        const auto run = [&](double seconds)
        {
            const auto end =
                std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
            auto next = std::chrono::steady_clock::now();
            while (std::chrono::steady_clock::now() < end)
            {
                sensor.doProcess();
                collect();
                next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
                std::this_thread::sleep_until(next);
            }
        };
        run(1.0);  // warm-up: windows fill, steering matrices are built
        warmupFrames = frames;
        warmupBearings = bearings;
        auto* worker = sensor.bearingWorker();
        const auto statsBefore = worker->stats();
        worker->takeLatency();
        const double cpu0 = cpuSeconds();
        run(duration);
        const double cpu = cpuSeconds() - cpu0;
        const auto lat = worker->takeLatency();
        const auto st = worker->stats();

        const uint64_t f = frames - warmupFrames, b = bearings - warmupBearings;
        const uint64_t skipped = st.skipped - statsBefore.skipped;
        std::printf(
            "algorithm %s, %.0f s: %llu frames (%.0f/s), %llu bearings (%.2f %% of frames), "
            "skipped %llu, rejected %llu\n"
            "latency frame complete -> bearing ready: p50 %.2f ms, p99 %.2f ms, max %.2f ms "
            "(%zu samples)\n"
            "CPU of the receiving process: %.0f %% of one core\n",
            argAlgo.getValue().c_str(), duration, static_cast<unsigned long long>(f),
            double(f) / duration, static_cast<unsigned long long>(b),
            f ? 100.0 * double(b) / double(f) : 0.0, static_cast<unsigned long long>(skipped),
            static_cast<unsigned long long>(st.rejected - statsBefore.rejected), lat.p50_s * 1e3,
            lat.p99_s * 1e3, lat.max_s * 1e3, lat.samples, 100.0 * cpu / duration);
        const bool met = f > 0 && double(b) >= 0.99 * double(f) && lat.p99_s <= 0.020;
        std::printf(
            "target (>= 99 %% with a bearing, p99 <= 20 ms): %s\n", met ? "met" : "NOT met");
        return 0;
    }
    catch (const std::exception& e)
    {
        std::cerr << "measure_live_bearings: " << e.what() << "\n";
        return 1;
    }
}
