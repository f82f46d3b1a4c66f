package dev.trailprint.app.sensors

import android.annotation.SuppressLint
import android.content.BroadcastReceiver
import android.content.Context
import android.content.Intent
import android.content.IntentFilter
import android.net.wifi.WifiManager
import android.os.SystemClock
import dev.trailprint.sensors.WifiReading
import dev.trailprint.sensors.WifiScan
import dev.trailprint.sensors.WifiScanSource
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow

/**
 * Wi-Fi scans through `WifiManager`: [requestScan] asks for one (the survey asks while it
 * handles a step, see `ScanPacer`), [results] emits each completed one, stamped with the
 * time the radio saw it (`ScanResult.timestamp`, since boot) rather than the time the
 * broadcast arrived, which may be later when the CPU was asleep. Android 9+ throttles
 * apps to 4 scans in 2 minutes unless "Wi-Fi scan throttling" is off in the developer
 * options; refused requests return false and the controller counts them.
 * Needs ACCESS_FINE_LOCATION granted and location turned on.
 */
class AndroidWifiScanSource(private val context: Context) : WifiScanSource {
    private val wifi = context.applicationContext.getSystemService(Context.WIFI_SERVICE) as WifiManager

    @SuppressLint("MissingPermission") // the survey asks for location before it starts
    override fun results(): Flow<WifiScan> = callbackFlow {
        val receiver = object : BroadcastReceiver() {
            override fun onReceive(c: Context, intent: Intent) {
                // EXTRA_RESULTS_UPDATED false: the scan failed or was throttled; the results
                // are the old ones, so they are not a new sample.
                if (!intent.getBooleanExtra(WifiManager.EXTRA_RESULTS_UPDATED, false)) return
                val results = wifi.scanResults
                val newestUs = results.maxOfOrNull { it.timestamp }
                val ageMs = newestUs?.let { SystemClock.elapsedRealtime() - it / 1000 }?.coerceAtLeast(0) ?: 0
                val readings = results.map {
                    WifiReading(bssid = it.BSSID, rssDbm = it.level, ssid = it.SSID, frequencyMhz = it.frequency)
                }
                trySend(WifiScan(System.currentTimeMillis() - ageMs, readings))
            }
        }
        context.registerReceiver(receiver, IntentFilter(WifiManager.SCAN_RESULTS_AVAILABLE_ACTION))
        awaitClose { context.unregisterReceiver(receiver) }
    }

    @Suppress("DEPRECATION") // still the only way for an app to ask for a scan
    override fun requestScan(): Boolean = wifi.startScan()
}
