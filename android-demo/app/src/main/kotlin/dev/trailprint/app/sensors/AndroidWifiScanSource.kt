package dev.trailprint.app.sensors

import android.annotation.SuppressLint
import android.content.BroadcastReceiver
import android.content.Context
import android.content.Intent
import android.content.IntentFilter
import android.net.wifi.WifiManager
import dev.trailprint.sensors.ScanIntervalStats
import dev.trailprint.sensors.WifiReading
import dev.trailprint.sensors.WifiScan
import dev.trailprint.sensors.WifiScanSource
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow
import kotlinx.coroutines.launch

/**
 * Wi-Fi scans through `WifiManager`: asks for a scan every interval and emits each
 * completed one. Android 9+ throttles foreground apps to 4 scans in 2 minutes unless
 * "Wi-Fi scan throttling" is off in the developer options; refused requests and real
 * completion times go to [stats], which the survey screen shows.
 * Needs ACCESS_FINE_LOCATION granted and location turned on.
 */
class AndroidWifiScanSource(
    private val context: Context,
    val stats: ScanIntervalStats = ScanIntervalStats(),
) : WifiScanSource {
    private val wifi = context.applicationContext.getSystemService(Context.WIFI_SERVICE) as WifiManager

    @SuppressLint("MissingPermission") // the survey screen asks for location before starting
    override fun scans(requestIntervalMs: Long): Flow<WifiScan> = callbackFlow {
        val receiver = object : BroadcastReceiver() {
            override fun onReceive(c: Context, intent: Intent) {
                // EXTRA_RESULTS_UPDATED false: the scan failed or was throttled; the results
                // are the old ones, so they are not a new sample.
                if (!intent.getBooleanExtra(WifiManager.EXTRA_RESULTS_UPDATED, false)) return
                val now = System.currentTimeMillis()
                stats.onScanCompleted(now)
                val readings = wifi.scanResults.map {
                    WifiReading(bssid = it.BSSID, rssDbm = it.level, ssid = it.SSID, frequencyMhz = it.frequency)
                }
                trySend(WifiScan(now, readings))
            }
        }
        context.registerReceiver(receiver, IntentFilter(WifiManager.SCAN_RESULTS_AVAILABLE_ACTION))
        val requester = launch {
            while (true) {
                @Suppress("DEPRECATION") // still the only way for an app to ask for a scan
                if (!wifi.startScan()) stats.onScanRequestRejected()
                delay(requestIntervalMs)
            }
        }
        awaitClose {
            requester.cancel()
            context.unregisterReceiver(receiver)
        }
    }
}
