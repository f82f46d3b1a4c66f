package dev.trailprint.app

import android.app.ActivityManager
import android.app.Application
import android.os.Build
import dev.trailprint.DeviceMemory
import dev.trailprint.Trailprint
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.Incoming
import dev.trailprint.team.WalkInbox
import dev.trailprint.team.WalkInboxModel
import dev.trailprint.survey.ActiveSurveyFile
import java.io.File
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.flow.MutableStateFlow

/** A file another app handed to Trailprint (share sheet, "open with"): its name and text. */
data class IncomingFile(val name: String, val text: String)

/**
 * Holds what the whole app shares: the one [Trailprint] (one database file), the record
 * of the active survey next to it, the export folder the FileProvider serves, and files
 * received from other apps until a screen takes them.
 */
class TrailprintApp : Application() {
    val api: Trailprint by lazy {
        // The engine's memory budget from this phone's RAM (DeviceMemory's rule), in every plan and session.
        val activityManager = getSystemService(ActivityManager::class.java)
        val memoryInfo = ActivityManager.MemoryInfo().also { activityManager.getMemoryInfo(it) }
        val budgetMb = DeviceMemory.budgetMb(memoryInfo.totalMem, activityManager.isLowRamDevice)
        Trailprint(TrailprintStore.open(File(filesDir, "trailprint.db").path), memoryBudgetMb = budgetMb)
    }

    val activeSurvey: ActiveSurveyFile by lazy { ActiveSurveyFile(File(filesDir, "active-survey.json")) }

    /** Exports go to cache/exports (res/xml/file_paths.xml), shared as content URIs. */
    val exports: ExportFiles by lazy { ExportFiles(File(cacheDir, "exports"), api) }

    /** This phone's name in the bundles it exports. */
    val deviceName: String get() = "${Build.MANUFACTURER} ${Build.MODEL}"

    /** The surveyor's name for bundles, remembered between surveys. */
    var surveyorName: String?
        get() = getSharedPreferences("trailprint", MODE_PRIVATE).getString("surveyor", null)
        set(v) = getSharedPreferences("trailprint", MODE_PRIVATE).edit().putString("surveyor", v).apply()

    /** Robot mode: a rosbridge WebSocket URL (`ws://robot.local:9090`), or null for the simulated robot. */
    @Volatile var rosbridgeUrl: String? = null

    /** Scope of what outlives a screen (the walk inbox). */
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Main.immediate)

    /** Walk files received on this phone, kept until opened ("Not opened"), and the dialog to open one. */
    val walks: WalkInboxModel by lazy { WalkInboxModel(api, scope, WalkInbox(File(filesDir, "walk-inbox"))) }

    /** Bundles shared to the app, waiting for the team screen (during a survey, until it ends). */
    val incomingBundles = MutableStateFlow<List<Incoming.Bundle>>(emptyList())

    /** Building files shared to the app, waiting for the buildings screen. */
    val incomingBuildings = MutableStateFlow<List<Incoming.Building>>(emptyList())

    /** The demo building shipped in the assets (android-demo/demo/demo-building.json). */
    fun demoBuildingJson(): String = assets.open("demo-building.json").bufferedReader().use { it.readText() }
}
