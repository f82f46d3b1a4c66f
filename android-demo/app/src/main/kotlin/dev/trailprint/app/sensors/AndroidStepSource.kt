package dev.trailprint.app.sensors

import android.content.Context
import android.hardware.Sensor
import android.hardware.SensorEvent
import android.hardware.SensorEventListener
import android.hardware.SensorManager
import dev.trailprint.sensors.PeakStepDetector
import dev.trailprint.sensors.StepEvent
import dev.trailprint.sensors.StepSource
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow

/**
 * Steps from `TYPE_STEP_DETECTOR` when the phone has one, else from the accelerometer
 * through the Android-free [PeakStepDetector]. Glue only: no logic of its own.
 */
class AndroidStepSource(context: Context) : StepSource {
    private val sensors = context.getSystemService(Context.SENSOR_SERVICE) as SensorManager

    /** True when the hardware step detector is used. */
    val usesStepDetector: Boolean = sensors.getDefaultSensor(Sensor.TYPE_STEP_DETECTOR) != null

    override fun steps(): Flow<StepEvent> = callbackFlow {
        val detector = sensors.getDefaultSensor(Sensor.TYPE_STEP_DETECTOR)
        val peaks = PeakStepDetector()
        val listener = object : SensorEventListener {
            override fun onSensorChanged(e: SensorEvent) {
                when (e.sensor.type) {
                    Sensor.TYPE_STEP_DETECTOR -> trySend(StepEvent(e.timestamp))
                    Sensor.TYPE_ACCELEROMETER ->
                        peaks.onSample(e.timestamp, e.values[0].toDouble(), e.values[1].toDouble(), e.values[2].toDouble())
                            ?.let { trySend(it) }
                }
            }

            override fun onAccuracyChanged(sensor: Sensor, accuracy: Int) = Unit
        }
        val sensor = detector ?: sensors.getDefaultSensor(Sensor.TYPE_ACCELEROMETER)
        if (sensor == null) {
            close(IllegalStateException("this phone has neither a step detector nor an accelerometer"))
            return@callbackFlow
        }
        sensors.registerListener(listener, sensor, SensorManager.SENSOR_DELAY_GAME)
        awaitClose { sensors.unregisterListener(listener) }
    }
}
