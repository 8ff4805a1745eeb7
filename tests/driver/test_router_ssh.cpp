// The router control transport against a real OpenSSH server on 127.0.0.1.
#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/RouterShell.h>

#include "SshdFixture.h"

using namespace mrpt_wifi;

namespace
{
SshOptions optionsFor(const test::SshdFixture& sshd)
{
    SshOptions o;
    o.host = "127.0.0.1";
    o.port = sshd.port();
    o.user = sshd.user();
    o.identityFile = sshd.clientKey();
    o.knownHostsFile = sshd.knownHosts();
    o.connectTimeout_s = 3;
    return o;
}

RouterErrorKind failureOf(SshRouterShell& shell, const std::string& cmd, double timeout = 10)
{
    try
    {
        shell.run(cmd, timeout);
    }
    catch (const RouterError& e)
    {
        return e.kind();
    }
    ADD_FAILURE() << "'" << cmd << "' did not fail";
    return RouterErrorKind::CommandFailed;
}
}  // namespace

TEST(RouterSsh, RunsCommandsWithKeyAuth)
{
    test::SshdFixture sshd;
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    for (bool persistent : {false, true})
    {
        auto o = optionsFor(sshd);
        o.persistentSession = persistent;
        SshRouterShell shell(o);
        EXPECT_EQ(shell.run("echo hello; echo world", 10), "hello\nworld\n");
        // A second command reuses the session when persistent.
        const auto t0 = std::chrono::steady_clock::now();
        EXPECT_EQ(shell.run("echo again", 10), "again\n");
        RecordProperty(
            persistent ? "second_command_ms_persistent_session" : "second_command_ms",
            int(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count()));
    }
}

TEST(RouterSsh, FailuresAreClassifiedWithinTheTimeout)
{
    test::SshdFixture sshd;
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    {
        auto o = optionsFor(sshd);
        o.identityFile = sshd.otherKey();  // not authorised
        SshRouterShell shell(o);
        EXPECT_EQ(failureOf(shell, "true"), RouterErrorKind::AuthenticationFailed);
    }
    {
        auto o = optionsFor(sshd);
        o.port = test::freeLoopbackPort();  // nobody listens
        SshRouterShell shell(o);
        const auto t0 = std::chrono::steady_clock::now();
        EXPECT_EQ(failureOf(shell, "true"), RouterErrorKind::Unreachable);
        EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
    }
    {
        auto o = optionsFor(sshd);
        o.knownHostsFile = sshd.dir().file("empty_known_hosts");  // never seen this router
        SshRouterShell shell(o);
        EXPECT_EQ(failureOf(shell, "true"), RouterErrorKind::HostKeyMismatch);
        o.acceptNewHostKey = true;  // explicit opt-in: remembered, then trusted
        SshRouterShell trusting(o);
        EXPECT_EQ(trusting.run("echo ok", 10), "ok\n");
        EXPECT_NE(test::readFile(o.knownHostsFile).find("ssh-ed25519"), std::string::npos);
    }
    {
        SshRouterShell shell(optionsFor(sshd));
        EXPECT_EQ(failureOf(shell, "nexutil -I eth6 -s500"), RouterErrorKind::CommandMissing);
        EXPECT_EQ(failureOf(shell, "exit 3"), RouterErrorKind::CommandFailed);
        const auto t0 = std::chrono::steady_clock::now();
        EXPECT_EQ(failureOf(shell, "sleep 30", 1.0), RouterErrorKind::Timeout);
        EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(4));
    }
}

TEST(RouterSsh, PasswordNeverOnTheCommandLine)
{
    SshOptions o;
    o.passwordEnvVar = "MRPT_WIFI_TEST_ROUTER_PASSWORD";
    SshRouterShell shell(o);
    const std::string secret = "s3cr3t-Pa55";
    ::setenv("MRPT_WIFI_TEST_ROUTER_PASSWORD", secret.c_str(), 1);
    for (const auto& arg : shell.sshArgv("wl -i eth6 chanspec 157/80"))
        EXPECT_EQ(arg.find(secret), std::string::npos) << arg;
    // The askpass helper hands the secret to ssh from its environment only.
    const auto r = runSubprocess(
        {test::binDir() + "/mrpt-wifi-askpass"}, 5, {{"MRPT_WIFI_ASKPASS_SECRET", secret}});
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.out, secret + "\n");
    EXPECT_NE(runSubprocess({test::binDir() + "/mrpt-wifi-askpass"}, 5).exitCode, 0);
    ::unsetenv("MRPT_WIFI_TEST_ROUTER_PASSWORD");
    // Without the variable: a clear error naming it, not a prompt or a hang.
    try
    {
        shell.run("true", 5);
        FAIL();
    }
    catch (const RouterError& e)
    {
        EXPECT_EQ(e.kind(), RouterErrorKind::AuthenticationFailed);
        EXPECT_NE(std::string(e.what()).find("MRPT_WIFI_TEST_ROUTER_PASSWORD"), std::string::npos);
    }
}
