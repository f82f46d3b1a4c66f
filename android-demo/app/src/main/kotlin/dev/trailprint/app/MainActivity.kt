package dev.trailprint.app

import android.content.Intent
import android.os.Bundle
import androidx.activity.ComponentActivity
import androidx.activity.compose.BackHandler
import androidx.activity.compose.setContent
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Surface
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.saveable.rememberSaveable
import androidx.compose.runtime.setValue
import androidx.lifecycle.lifecycleScope
import dev.trailprint.AppException
import dev.trailprint.app.survey.SurveyService
import dev.trailprint.app.ui.BuildingsScreen
import dev.trailprint.app.ui.FinishScreen
import dev.trailprint.app.ui.PlanScreen
import dev.trailprint.app.ui.SurveyScreen
import dev.trailprint.app.ui.TeamScreen
import dev.trailprint.app.ui.WalkScreen
import dev.trailprint.team.WalkFiles
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/**
 * Hosts the navigation between the screens; each screen has its ViewModel. Files shared to
 * the app go to the walk screen (a walk file) or the team screen (bundles). A survey
 * recorded as active (the app was killed during it) is brought back at launch.
 */
class MainActivity : ComponentActivity() {
    private val jump = MutableStateFlow<String?>(null)

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        val app = application as TrailprintApp
        if (savedInstanceState == null) {
            val active = try {
                app.activeSurvey.read()
            } catch (e: AppException) {
                null // the survey screen's lifecycle reports the unreadable record
            }
            if (active != null) {
                SurveyService.restore(this)
                jump.value = Routes.survey(null, active.mode == dev.trailprint.survey.SurveyMode.ROBOT)
            }
            receive(intent)
        }
        setContent {
            MaterialTheme {
                Surface { AppNavigation(jump) }
            }
        }
    }

    override fun onNewIntent(intent: Intent) {
        super.onNewIntent(intent)
        receive(intent)
    }

    private fun receive(intent: Intent) {
        val uris = intent.documents()
        if (uris.isEmpty()) return
        val app = application as TrailprintApp
        lifecycleScope.launch {
            val files = withContext(Dispatchers.IO) { uris.mapNotNull { runCatching { readDocument(it) }.getOrNull() } }
            if (files.isEmpty()) return@launch
            app.incoming.value = files
            jump.value = if (WalkFiles.looksLikeWalkFile(files.first().text)) Routes.WALK else Routes.TEAM
        }
    }
}

/** Where the app is: a route string, saved across configuration changes. */
private object Routes {
    const val BUILDINGS = "buildings"
    const val TEAM = "team"
    const val WALK = "walk"
    fun plan(buildingId: Long) = "plan/$buildingId"
    /** [planId] null: the survey already running. */
    fun survey(planId: Long?, robot: Boolean) = "survey/${planId ?: "running"}/$robot"
    fun finish(sessionId: Long) = "finish/$sessionId"
}

@Composable
private fun AppNavigation(jump: MutableStateFlow<String?>) {
    var route by rememberSaveable { mutableStateOf(Routes.BUILDINGS) }
    LaunchedEffect(Unit) {
        jump.collect { r -> if (r != null) { route = r; jump.value = null } }
    }
    val parts = route.split('/')
    BackHandler(enabled = route != Routes.BUILDINGS) { route = Routes.BUILDINGS }
    when (parts[0]) {
        "plan" -> PlanScreen(
            buildingId = parts[1].toLong(),
            onStartSurvey = { planId, robot -> route = Routes.survey(planId, robot) },
        )
        "survey" -> SurveyScreen(
            planId = parts[1].toLongOrNull(),
            robot = parts[2].toBoolean(),
            onFinished = { sessionId -> route = Routes.finish(sessionId) },
            rosbridgeUrl = (androidx.compose.ui.platform.LocalContext.current.applicationContext as TrailprintApp).rosbridgeUrl,
        )
        "finish" -> FinishScreen(sessionId = parts[1].toLong(), onDone = { route = Routes.BUILDINGS })
        Routes.TEAM -> TeamScreen()
        Routes.WALK -> WalkScreen(onStart = { planId -> route = Routes.survey(planId, false) }, onBack = { route = Routes.BUILDINGS })
        else -> BuildingsScreen(
            onOpen = { id -> route = Routes.plan(id) },
            onTeam = { route = Routes.TEAM },
            onWalkFile = { route = Routes.WALK },
        )
    }
}
