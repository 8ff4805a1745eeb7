#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/NexmonRouterControl.h>

using namespace mrpt_wifi;

namespace
{
/** Records commands and answers with canned output. */
class RecordingShell : public RouterShell
{
public:
    std::vector<std::string> commands;
    std::string answer;
    std::string run(const std::string& command, double) override
    {
        commands.push_back(command);
        return answer;
    }
    std::string describe() const override { return "recording"; }
};
}  // namespace

TEST(NexmonRouterControl, ConfigureIsOneRoundTripWithWirosCommands)
{
    auto shell = std::make_shared<RecordingShell>();
    NexmonRouterControl router(shell, {});
    CsiExtractionSettings s;
    s.chanspec = Chanspec::fromString("42/80");
    s.coreMask = 0x3;
    s.streamMask = 0x1;
    s.macFilter = {MacAddress::fromString("00:12:34:56:78:9b")};
    s.delay = 80;
    router.configure(s);
    ASSERT_EQ(shell->commands.size(), 1u);
    EXPECT_EQ(
        shell->commands[0],
        "wl -i eth6 chanspec 36/80 && wl -i eth6 monitor 1 && nexutil -I eth6 -s500 -b -l34 -v "
        "$(makecsiparams -e 1 -c 36/80 -C 0x3 -N 0x1 -m 00:12:34:56:78:9b -d 80)");
    s.macFilter.assign(5, MacAddress{});
    EXPECT_THROW(router.configure(s), std::invalid_argument);
}

TEST(NexmonRouterControl, ModuleLoadAndTwoPointFourGigahertz)
{
    auto shell = std::make_shared<RecordingShell>();
    RouterSetupOptions o;
    o.modulePath = "/jffs/nexmon/dhd.ko";
    NexmonRouterControl router(shell, o);
    router.loadFirmwareModule();
    EXPECT_EQ(
        shell->commands.back(), "rmmod dhd; insmod /jffs/nexmon/dhd.ko && brctl addif br0 eth6");
    CsiExtractionSettings s;
    s.chanspec = Chanspec::fromString("6/20");
    router.configure(s);
    EXPECT_EQ(shell->commands.back().rfind("wl -i eth5 chanspec 6/20", 0), 0u)
        << shell->commands.back();
}

TEST(NexmonRouterControl, ReadsTheCurrentChanspec)
{
    auto shell = std::make_shared<RecordingShell>();
    NexmonRouterControl router(shell, {});
    shell->answer = "157/80 (0xe29b)\n";
    EXPECT_EQ(router.currentChanspec().raw, 0xe29b);
    shell->answer = "36/80\n";
    EXPECT_EQ(router.currentChanspec().centerChannel, 42);
    shell->answer = "wl: Unsupported\n";
    EXPECT_THROW(router.currentChanspec(), RouterError);
}

TEST(NexmonRouterControl, TransmitterLoopIsBoundedAndKeepsTheWholeMac)
{
    auto shell = std::make_shared<RecordingShell>();
    NexmonRouterControl router(shell, {});
    TransmitterSettings t;
    t.source = MacAddress::fromString("02:4d:52:50:54:2a");
    t.count = 500;
    t.rate_Hz = 100;
    t.streams = 4;
    router.startTransmitter(t);
    const auto& cmd = shell->commands.back();
    EXPECT_NE(cmd.find("5g_rate -v 0 -s 4"), std::string::npos) << cmd;
    EXPECT_NE(cmd.find("-lt 500 ]"), std::string::npos) << cmd;
    EXPECT_NE(cmd.find("usleep 10000"), std::string::npos) << cmd;
    // The frame: addr2 carries all six bytes (WiROS's script corrupts the sixth).
    const auto frame = makeBeaconFrame(t.source, "mrpt_wifi", 0);
    EXPECT_EQ(
        std::vector<uint8_t>(frame.begin() + 10, frame.begin() + 16),
        std::vector<uint8_t>(t.source.bytes.begin(), t.source.bytes.end()));
    EXPECT_EQ(frame[0], 0x80);
}

TEST(NexmonRouterControl, ShellValuesAreValidatedAndQuoted)
{
    auto shell = std::make_shared<RecordingShell>();
    RouterSetupOptions o;
    o.interface5G = "eth6; reboot";
    try
    {
        NexmonRouterControl router(shell, o);
        ADD_FAILURE() << "an interface name with a ';' was accepted";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("setup_interface_5g"), std::string::npos) << e.what();
    }
    o = RouterSetupOptions();
    o.modulePath = "/jffs/dhd.ko\nreboot";
    EXPECT_THROW(NexmonRouterControl(shell, o), std::invalid_argument);
    EXPECT_TRUE(shell->commands.empty());

    // Safe words stay as they are; anything else becomes one single-quoted word.
    EXPECT_EQ(shellQuote("/jffs/nexmon/dhd.ko"), "/jffs/nexmon/dhd.ko");
    EXPECT_EQ(shellQuote("eth6; reboot"), "'eth6; reboot'");
    EXPECT_EQ(shellQuote("it's"), "'it'\\''s'");
    EXPECT_EQ(shellQuote(""), "''");
}
