/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * mrpt-wifi-askpass: the SSH_ASKPASS helper of the router connection. ssh runs it to ask for
 * the router password; it answers with MRPT_WIFI_ASKPASS_SECRET, which the driver puts only
 * in ssh's environment. The password never touches argv, logs or files. */
#include <cstdio>
#include <cstdlib>

int main()
{
    const char* secret = std::getenv("MRPT_WIFI_ASKPASS_SECRET");
    if (!secret)
    {
        std::fputs("mrpt-wifi-askpass: no password provided by the driver\n", stderr);
        return 1;
    }
    std::printf("%s\n", secret);
    return 0;
}
