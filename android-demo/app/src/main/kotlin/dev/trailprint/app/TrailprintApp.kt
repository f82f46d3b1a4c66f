package dev.trailprint.app

import android.app.Application
import dev.trailprint.Trailprint
import dev.trailprint.ffi.TrailprintStore
import java.io.File

/** Holds the one [Trailprint] of the app (one database file, shared by every screen). */
class TrailprintApp : Application() {
    val api: Trailprint by lazy {
        Trailprint(TrailprintStore.open(File(filesDir, "trailprint.db").path))
    }

    /** Robot mode: a rosbridge WebSocket URL (`ws://robot:9090`), or null for the simulated robot. */
    @Volatile var rosbridgeUrl: String? = null

    /** The demo building shipped in the assets (android-demo/demo/demo-building.json). */
    fun demoBuildingJson(): String = assets.open("demo-building.json").bufferedReader().use { it.readText() }
}
