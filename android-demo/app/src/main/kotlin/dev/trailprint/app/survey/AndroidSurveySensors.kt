package dev.trailprint.app.survey

import android.Manifest
import android.content.Context
import android.content.pm.PackageManager
import android.os.Build
import androidx.core.content.ContextCompat
import dev.trailprint.app.sensors.AndroidStepSource
import dev.trailprint.app.sensors.AndroidWifiScanSource
import dev.trailprint.app.sensors.OkHttpWebSocketFactory
import dev.trailprint.robot.RobotDriver
import dev.trailprint.robot.RosbridgeConfig
import dev.trailprint.robot.RosbridgeRobotDriver
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.sensors.StepSource
import dev.trailprint.sensors.WifiScanSource
import dev.trailprint.survey.SurveySensors

/** The phone's sensors for [dev.trailprint.survey.SurveyLifecycle]. */
class AndroidSurveySensors(private val context: Context) : SurveySensors {
    private val wifi by lazy { AndroidWifiScanSource(context) }

    /** The step detector when ACTIVITY_RECOGNITION is granted, else the accelerometer. */
    override fun steps(): StepSource = AndroidStepSource(
        context,
        useStepDetector = Build.VERSION.SDK_INT < 29 ||
            ContextCompat.checkSelfPermission(context, Manifest.permission.ACTIVITY_RECOGNITION) == PackageManager.PERMISSION_GRANTED,
    )

    override fun wifi(): WifiScanSource = wifi

    override fun robot(rosbridgeUrl: String?): RobotDriver =
        rosbridgeUrl?.let { RosbridgeRobotDriver(OkHttpWebSocketFactory(), RosbridgeConfig(url = it)) }
            // On the wall clock: a restarted survey's poses must not go back in time.
            ?: SimulatedRobot(SimulatedRobotConfig(speed = 0.5, startTimeMs = System.currentTimeMillis()))
}
