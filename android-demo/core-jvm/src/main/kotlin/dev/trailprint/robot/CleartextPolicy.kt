package dev.trailprint.robot

import java.net.URI
import java.net.URISyntaxException

/**
 * Where the app may speak plain `ws://` — the same hosts as the app's
 * `res/xml/network_security_config.xml`, which Android (and OkHttp with it) enforces:
 * `localhost`, `127.0.0.1`, the emulator's host `10.0.2.2`, and mDNS names under
 * `.local` (a robot on the local network announces itself as `robot.local`). Everything
 * else needs `wss://`. The config cannot name address ranges (it matches host names), so
 * a robot known only by a numeric address must be given an mDNS name or added to the
 * config; [check] says so before the connection is tried.
 */
object CleartextPolicy {
    val hosts: List<String> = listOf("localhost", "127.0.0.1", "10.0.2.2")
    const val MDNS_SUFFIX = ".local"

    /** Null when the app may connect to [url]; else why not, naming the URL. */
    fun check(url: String): String? {
        val uri = try {
            URI(url.trim())
        } catch (e: URISyntaxException) {
            return "$url: not a URL (${e.reason})"
        }
        val scheme = uri.scheme?.lowercase()
        val host = uri.host?.lowercase()?.trimEnd('.')
        return when {
            scheme == "wss" && host != null -> null
            scheme != "ws" -> "$url: expected a ws:// or wss:// URL"
            host == null -> "$url: no host in the URL"
            host in hosts || host.endsWith(MDNS_SUFFIX) || host == MDNS_SUFFIX.drop(1) -> null
            else -> "$url: plain ws:// is allowed only to localhost, 10.0.2.2 and *.local names; " +
                "use wss://, the robot's mDNS name (ws://robot.local:9090), or add $host to res/xml/network_security_config.xml"
        }
    }
}
