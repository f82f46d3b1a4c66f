package dev.trailprint.app

import android.os.Bundle
import androidx.activity.ComponentActivity
import androidx.activity.compose.BackHandler
import androidx.activity.compose.setContent
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Surface
import androidx.compose.runtime.Composable
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.saveable.rememberSaveable
import androidx.compose.runtime.setValue
import androidx.compose.ui.platform.LocalContext
import dev.trailprint.app.ui.BuildingsScreen
import dev.trailprint.app.ui.FinishScreen
import dev.trailprint.app.ui.PlanScreen
import dev.trailprint.app.ui.SurveyScreen

/** Only hosts the navigation between the four screens; each screen has its ViewModel. */
class MainActivity : ComponentActivity() {
    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        setContent {
            MaterialTheme {
                Surface { AppNavigation() }
            }
        }
    }
}

/** Where the app is: a route string, saved across configuration changes. */
private object Routes {
    const val BUILDINGS = "buildings"
    fun plan(buildingId: Long) = "plan/$buildingId"
    fun survey(planId: Long, robot: Boolean) = "survey/$planId/$robot"
    fun finish(sessionId: Long) = "finish/$sessionId"
}

@Composable
private fun AppNavigation() {
    var route by rememberSaveable { mutableStateOf(Routes.BUILDINGS) }
    val parts = route.split('/')
    BackHandler(enabled = route != Routes.BUILDINGS) { route = Routes.BUILDINGS }
    when (parts[0]) {
        "plan" -> PlanScreen(
            buildingId = parts[1].toLong(),
            onStartSurvey = { planId, robot -> route = Routes.survey(planId, robot) },
        )
        "survey" -> SurveyScreen(
            planId = parts[1].toLong(),
            robot = parts[2].toBoolean(),
            onFinished = { sessionId -> route = Routes.finish(sessionId) },
            rosbridgeUrl = (LocalContext.current.applicationContext as TrailprintApp).rosbridgeUrl,
        )
        "finish" -> FinishScreen(sessionId = parts[1].toLong(), onDone = { route = Routes.BUILDINGS })
        else -> BuildingsScreen(onOpen = { id -> route = Routes.plan(id) })
    }
}
