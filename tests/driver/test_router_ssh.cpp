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

// ---- what a user reads when ssh fails: the cause, not ssh's first line

namespace
{
std::string failureMessage(const SshOptions& o)
{
    SshRouterShell shell(o);
    try
    {
        shell.run("true", 10);
    }
    catch (const RouterError& e)
    {
        return e.what();
    }
    ADD_FAILURE() << "did not fail";
    return "";
}
bool has(const std::string& s, const std::string& what)
{
    return s.find(what) != std::string::npos;
}
}  // namespace

TEST(RouterSsh, SshFailuresNameTheirCauseAndWhatToCheck)
{
    test::SshdFixture sshd;
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    const std::string missingKey = sshd.dir().file("no_such_key");
    for (bool persistent : {false, true})
    {
        SCOPED_TRACE(persistent ? "persistent session" : "one ssh per command");
        auto base = optionsFor(sshd);
        base.persistentSession = persistent;
        {
            // Nobody listens, and the key file is missing: ssh's first line is the key warning,
            // the cause is the refused connection.
            auto o = base;
            o.port = test::freeLoopbackPort();
            o.identityFile = missingKey;
            const auto m = failureMessage(o);
            EXPECT_TRUE(has(m, "router unreachable")) << m;
            EXPECT_TRUE(
                has(m, "connection refused: nothing accepts ssh on 127.0.0.1 port " +
                           std::to_string(o.port)))
                << m;
            EXPECT_TRUE(has(m, "Identity file " + missingKey + " not accessible")) << m;
        }
        {
            auto o = base;
            o.identityFile = missingKey;  // the server is there: no key to offer
            const auto m = failureMessage(o);
            EXPECT_TRUE(has(m, "authentication failed: the router rejected the key " + missingKey))
                << m;
            EXPECT_TRUE(has(m, "names a key file that does not exist")) << m;
        }
        {
            auto o = base;
            o.identityFile = sshd.otherKey();
            const auto m = failureMessage(o);
            EXPECT_TRUE(has(m, "Authorized Keys")) << m;
        }
        {
            auto o = base;
            o.knownHostsFile = sshd.dir().file("empty_known_hosts");
            const auto m = failureMessage(o);
            EXPECT_TRUE(has(m, "host key is not in " + o.knownHostsFile)) << m;
            EXPECT_TRUE(has(m, "login_accept_new_host_key")) << m;
        }
        {
            // Another key stored for this router: what a re-flashed router looks like.
            auto o = base;
            o.knownHostsFile = sshd.dir().file("changed_known_hosts");
            std::ofstream(o.knownHostsFile) << "[127.0.0.1]:" << sshd.port() << " "
                                            << test::readFile(sshd.dir().file("other_key.pub"));
            const auto m = failureMessage(o);
            EXPECT_TRUE(has(m, "host key changed")) << m;
            EXPECT_TRUE(has(m, "ssh-keygen -R '[127.0.0.1]:" + std::to_string(sshd.port()))) << m;
        }
    }
}

TEST(RouterSsh, CausesThatLoopbackCannotProduceAreExplainedFromSshsWords)
{
    // OpenSSH 9.2's messages for a dead host, a missing route and an unknown name.
    SshOptions o;
    o.host = "192.168.50.1";
    EXPECT_TRUE(has(
        explainSshFailure("ssh: connect to host 192.168.50.1 port 22: Connection timed out\n", o),
        "connection timed out: no answer from 192.168.50.1 port 22"));
    EXPECT_TRUE(
        has(explainSshFailure("ssh: connect to host 192.168.50.1 port 22: No route to host\n", o),
            "no route to 192.168.50.1"));
    o.host = "router.lan";
    EXPECT_TRUE(
        has(explainSshFailure(
                "ssh: Could not resolve hostname router.lan: Name or service not known\n", o),
            "cannot resolve the host name 'router.lan'"));
    EXPECT_TRUE(
        has(explainSshFailure("kex_exchange_identification: read: Connection reset by peer\n", o),
            "closed the connection before login"));
}

TEST(CsiRouterCli, ReportsTheSshCauseWithExitStatus4AndNeverThePassword)
{
    test::SshdFixture sshd;
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    const std::string csiRouter = test::binDir() + "/csi-router status --host 127.0.0.1 --user " +
                                  sshd.user() + " --known-hosts " + sshd.knownHosts();
    {
        const auto r = test::run(
            csiRouter + " --port " + std::to_string(test::freeLoopbackPort()) + " -i " +
            sshd.dir().file("no_such_key"));
        EXPECT_EQ(r.exitCode, 4) << r.output;
        EXPECT_TRUE(has(r.output, "connection refused")) << r.output;
        EXPECT_TRUE(has(r.output, "no_such_key")) << r.output;
    }
    {
        // A password login the server refuses: the cause, and the password nowhere.
        const std::string secret = "Pa55-w0rd-never-shown";
        const auto r = test::run(
            "MRPT_WIFI_TEST_ROUTER_PASSWORD='" + secret + "' " + csiRouter + " --port " +
            std::to_string(sshd.port()) + " --password-env MRPT_WIFI_TEST_ROUTER_PASSWORD");
        EXPECT_EQ(r.exitCode, 4) << r.output;
        EXPECT_TRUE(has(r.output, "authentication failed")) << r.output;
        EXPECT_TRUE(has(r.output, "$MRPT_WIFI_TEST_ROUTER_PASSWORD")) << r.output;
        EXPECT_FALSE(has(r.output, secret)) << r.output;
    }
    {
        // Reachable, key accepted, but not a Nexmon router: a router command failed.
        const auto r = test::run(
            csiRouter + " --port " + std::to_string(sshd.port()) + " -i " + sshd.clientKey());
        EXPECT_EQ(r.exitCode, 4) << r.output;
        EXPECT_TRUE(has(r.output, "command missing on router")) << r.output;
    }
    const auto usage = test::run(test::binDir() + "/csi-router no-such-command");
    EXPECT_EQ(usage.exitCode, 1) << usage.output;
}
