// The loopback rule, the shim protocol and how a shim finds the emulator's socket.
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/ControlSocket.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/emulator/LoopbackUdp.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "EmulatorTestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::emulator;

TEST(EmulatorLoopback, AcceptsOnlyLoopbackDestinations)
{
    for (const char* ok : {"127.0.0.1", "127.1.2.3", "::1", "localhost"})
        EXPECT_NO_THROW(loopbackDestination(ok, 5500)) << ok;
    EXPECT_EQ(loopbackDestination("::1", 5500).asString(), "[::1]:5500");
    for (const char* bad :
         {"192.168.1.10", "10.10.10.10", "255.255.255.255", "0.0.0.0", "::ffff:127.0.0.1",
          "fe80::1", "router.local", "", "128.0.0.1"})
    {
        try
        {
            loopbackDestination(bad, 5500);
            ADD_FAILURE() << "accepted " << bad;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find("refusing"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(loopbackDestination("127.0.0.1", 0), std::invalid_argument);
}

TEST(EmulatorLoopback, EmulatorRefusesANonLoopbackDestinationBeforeSending)
{
    EmulatorOptions o;
    o.scenario = test::emulatorTestScenario();
    o.destinationHost = "192.168.50.1";
    EXPECT_THROW(Emulator e(o), std::invalid_argument);
    o.destinationHost = "255.255.255.255";
    EXPECT_THROW(Emulator e(o), std::invalid_argument);
}

TEST(EmulatorControl, ProtocolRoundTrip)
{
    const Argv argv = {"wl", "-i", "eth6", "chanspec", std::string("with\0nul", 8), ""};
    const std::string req = protocol::encodeRequest(argv);
    Argv back;
    EXPECT_FALSE(protocol::decodeRequest(req.substr(0, req.size() - 3), back));  // partial
    ASSERT_TRUE(protocol::decodeRequest(req, back));
    EXPECT_EQ(back, argv);
    EXPECT_THROW(protocol::decodeRequest("XXXX" + req.substr(4), back), std::invalid_argument);

    const ToolResult r{3, "out\n", std::string("err\0x", 5)};
    const std::string resp = protocol::encodeResponse(r);
    ToolResult rb;
    EXPECT_FALSE(protocol::decodeResponse(resp.substr(0, 9), rb));
    ASSERT_TRUE(protocol::decodeResponse(resp, rb));
    EXPECT_EQ(rb.exitCode, 3);
    EXPECT_EQ(rb.out, r.out);
    EXPECT_EQ(rb.err, r.err);
}

TEST(EmulatorControl, ShimFindsTheSocketFromEnvironmentLinkPathOrPath)
{
    test::TempDir tmp;
    const std::string bin = tmp.file("bin");
    std::filesystem::create_directories(bin);
    const std::string wl = bin + "/wl";
    std::ofstream(wl) << "#!/bin/sh\n";
    ::chmod(wl.c_str(), 0755);

    EXPECT_EQ(findEmulatorSocket(wl, "/x/e.sock", nullptr), "/x/e.sock");
    EXPECT_EQ(findEmulatorSocket(wl, "", nullptr), bin + "/../emulator.sock");
    // Bare name, as a shell running it through $PATH passes it.
    const std::string path = "/nonexistent:" + bin + ":/usr/bin";
    EXPECT_EQ(findEmulatorSocket("wl", nullptr, path.c_str()), bin + "/../emulator.sock");
    EXPECT_EQ(findEmulatorSocket("wl", nullptr, "/nonexistent"), "");
}

TEST(EmulatorControl, SocketAnswersCommandsAndRefusesASecondEmulator)
{
    test::TempDir tmp;
    test::UdpReceiver rx;
    test::RunningEmulator emu(test::testOptions(rx.port(), tmp.path().string()));
    const auto r = emu.call({"wl", "-i", "eth6", "chanspec"});
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.out, "100/80 (0xe06a)\n");  // the stock firmware's channel after boot
    EXPECT_NE(emu.call({"emulator-ctl", "nonsense"}).exitCode, 0);
    EXPECT_NE(emu.call({"emulator-ctl", "faults", "--loss", "2"}).exitCode, 0);
    // Same state directory: refused while the first one is alive.
    EXPECT_THROW(
        Emulator second(test::testOptions(rx.port(), tmp.path().string())), std::runtime_error);
    emu.stop();
    EXPECT_EQ(rx.count(), 0u);  // never configured: nothing sent
}
