/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * mrpt-wifi-askpass: the SSH_ASKPASS helper of the router connection. ssh runs it to ask for
 * the router password; it answers with MRPT_WIFI_ASKPASS_SECRET, which the driver puts only
 * in ssh's environment. The password never touches argv, logs or files. */
#include <cstdio>
#include <cstdlib>
#include <cstring>

int main(int argc, char** argv)
{
    // ssh passes its prompt ("user@host's password: "), never a lone --help.
    if (argc == 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")))
    {
        std::puts(
            "Usage: mrpt-wifi-askpass [PROMPT]\n"
            "The SSH_ASKPASS helper of CWiFiCSISensor and csi-router: not run by hand. ssh runs\n"
            "it to ask for the router password (login_password_env in the .ini, csi-router\n"
            "--password-env); it prints MRPT_WIFI_ASKPASS_SECRET, which the driver puts only in\n"
            "ssh's environment, so the password never touches argv, logs or files.\n"
            "Exit status: 0 answered; 1 MRPT_WIFI_ASKPASS_SECRET not set (not run by the driver).");
        return 0;
    }
    const char* secret = std::getenv("MRPT_WIFI_ASKPASS_SECRET");
    if (!secret)
    {
        std::fputs("mrpt-wifi-askpass: no password provided by the driver\n", stderr);
        return 1;
    }
    std::printf("%s\n", secret);
    return 0;
}
