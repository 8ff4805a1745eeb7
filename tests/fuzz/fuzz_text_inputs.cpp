// libFuzzer target for the localization programs' text inputs: the first byte chooses the
// reader, the rest is the file's text.
//   0  bearings CSV (readBearingCsv, names resolved through a small map)
//   1  TUM trajectory (Trajectory2D::fromTumFile)
//   2  WSR-style CSV trajectory (Trajectory2D::fromWsrCsv)
//   3  AP map YAML (TransmitterMap::fromYamlText)
//   4  .ini (the project's sections: [UnknownMotion], [OdometryMotion], [ParticleRecovery],
//      [WindowSmoother], [wifi-localize], the wifiBearingMap definition and its area against
//      the init_PDF box, and wifi-pf-localization's no-odometry rawlog built from a few
//      bearings with the [UnknownMotion] read)
// Each reader must either give a result or throw a std::exception with a message; a crash,
// a sanitizer report or an exception of another type is a failure. The readers take paths:
// the text goes through one temporary file per process.
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
const std::string& scratchFile()
{
    static const std::string path =
        "/tmp/mrpt_wifi_fuzz_text_" + std::to_string(::getpid()) + ".txt";
    return path;
}

std::string writeScratch(const std::string& text)
{
    std::ofstream(scratchFile(), std::ios::binary) << text;
    return scratchFile();
}

const TransmitterMap& names()
{
    static const TransmitterMap m = TransmitterMap::fromYamlText(
        "transmitters:\n"
        "  - {name: ap-a, mac: '02:00:00:00:0a:01', position: [0.5, 0.5], yaw_deg: 45}\n"
        "  - {name: ap-b, mac: '02:00:00:00:0a:02', position: [9.5, 4.5], yaw_deg: -135}\n");
    return m;
}

void requireFinite(double v)
{
    if (!std::isfinite(v)) __builtin_trap();  // a reader let a non-finite number through
}

void bearingCsv(const std::string& text)
{
    BearingCsvOptions o;
    o.names = &names();
    InputWarnings w;
    for (const auto& b : readBearingCsv(writeScratch(text), o, &w))
    {
        requireFinite(b.t);
        if (b.hasAoa) requireFinite(b.aoa), requireFinite(b.aoaStd);
        if (b.hasAod) requireFinite(b.aod), requireFinite(b.aodStd);
    }
    (void)w.csvWarning("x");
}

void trajectory(const std::string& text, bool tum)
{
    const auto path = writeScratch(text);
    const auto t = tum ? Trajectory2D::fromTumFile(path) : Trajectory2D::fromWsrCsv(path);
    for (size_t i = 0; i < t.size(); ++i)
    {
        requireFinite(t.t[i]);
        requireFinite(t.poses[i].x), requireFinite(t.poses[i].y), requireFinite(t.poses[i].phi);
        mrpt::math::TPose2D p;
        (void)t.interpolate(t.t[i], p, 0.5);
    }
}

void apMap(const std::string& text)
{
    const auto m = TransmitterMap::fromYamlText(text, "<fuzz>", "/nonexistent");
    (void)m.asYamlText();
    for (const auto& t : m.transmitters())
        requireFinite(t.pose.x), requireFinite(t.pose.y), requireFinite(t.pose.phi);
}

// Each section on its own: one bad value must not hide the readers after it.
template <typename F>
void guarded(F&& f)
{
    try
    {
        f();
    }
    catch (const std::exception& e)
    {
        if (std::string(e.what()).empty()) __builtin_trap();  // an error must say something
    }
}

void iniText(const std::string& text)
{
    mrpt::config::CConfigFileMemory ini;
    ini.setContent(text);
    UnknownMotion motion;
    bool motionOk = false;
    guarded(
        [&]
        {
            motion.loadFromConfigFile(ini, "UnknownMotion");
            motionOk = true;
        });
    guarded(
        [&]
        {
            OdometryMotion m;
            m.loadFromConfigFile(ini, "OdometryMotion");
            (void)m.makeAction(0.1, mrpt::poses::CPose2D(0.1, 0, 0));
        });
    guarded(
        [&]
        {
            ParticleRecoveryOptions r;
            r.loadFromConfigFile(ini, "ParticleRecovery");
        });
    guarded(
        [&]
        {
            WindowSmootherOptions s;
            s.loadFromConfigFile(ini, "WindowSmoother");
        });
    guarded(
        [&]
        {
            LiveLocalizerOptions l;
            l.loadFromConfigFile(ini, "wifi-localize");
        });
    guarded(
        [&]
        {
            // The map definition as MRPT's apps read it; the transmitters file is not there,
            // so creation stops at it at the latest.
            mrpt::maps::TSetOfMetricMapInitializers inits;
            inits.loadFromConfigFile(ini, "MetricMap");
            mrpt::maps::CMultiMetricMap maps;
            maps.setListOfMaps(inits);
            if (auto map = maps.mapByClass<CWiFiBearingMap>())
            {
                std::string warning;
                boundByInitialPdf(*map, ini, &warning);
            }
        });
    guarded([&] { (void)initialPdfArea(ini); });
    if (!motionOk) return;
    // The no-odometry path: the walk's actions must stay usable by MRPT's filter for any
    // accepted [UnknownMotion].
    for (const double dt : {0.0, 0.01, 0.5, 1e3})
    {
        const auto a = motion.makeAction(dt, mrpt::poses::CPose2D(0.05, 0, 0.01));
        mrpt::obs::CActionCollection acts;
        acts.insert(*a);
        if (!acts.getBestMovementEstimation()) __builtin_trap();
        const auto r = withReseeding(*a, 0.5, 1e3);
        mrpt::obs::CActionCollection reseeded;
        reseeded.insert(r);
        if (!reseeded.getBestMovementEstimation()) __builtin_trap();
    }
}
}  // namespace

// MRPT 2.5.8's YAML reader leaks libfyaml's parser and input on some syntax errors ("wrongly
// indented block sequence in flow mode", malformed UTF-8): not this project's memory. Every
// other leak still fails the run (LeakSanitizer reads this hook; other builds ignore it).
extern "C" const char* __lsan_default_suppressions()
{
    return "leak:libfyaml.so\n";
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size == 0) return 0;
    const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
    const int reader = data[0] % 5;
    try
    {
        switch (reader)
        {
            case 0:
                bearingCsv(text);
                break;
            case 1:
                trajectory(text, true);
                break;
            case 2:
                trajectory(text, false);
                break;
            case 3:
                apMap(text);
                break;
            default:
                iniText(text);
                break;
        }
    }
    catch (const std::exception& e)
    {
        if (std::string(e.what()).empty()) __builtin_trap();  // an error must say something
    }
    return 0;
}
