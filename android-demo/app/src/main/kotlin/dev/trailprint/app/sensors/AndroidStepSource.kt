package dev.trailprint.app.sensors

import android.content.Context
import android.hardware.Sensor
import android.hardware.SensorEvent
import android.hardware.SensorEventListener
import android.hardware.SensorManager
import android.os.PowerManager
import dev.trailprint.sensors.PeakStepDetector
import dev.trailprint.sensors.StepEvent
import dev.trailprint.sensors.StepSource
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow

/**
 * Steps from `TYPE_STEP_DETECTOR` — its wake-up variant where the phone has one, so that a
 * step wakes the CPU in a pocket — when [useStepDetector] (ACTIVITY_RECOGNITION granted);
 * else from the accelerometer through the Android-free [PeakStepDetector]. The
 * accelerometer needs every sample, so that fallback keeps the CPU awake (its own partial
 * wake lock) for as long as steps are collected. Glue only: no logic of its own.
 */
class AndroidStepSource(private val context: Context, private val useStepDetector: Boolean) : StepSource {
    private val sensors = context.getSystemService(Context.SENSOR_SERVICE) as SensorManager

    override fun steps(): Flow<StepEvent> = callbackFlow {
        val detector = if (useStepDetector) {
            sensors.getDefaultSensor(Sensor.TYPE_STEP_DETECTOR, true) ?: sensors.getDefaultSensor(Sensor.TYPE_STEP_DETECTOR)
        } else {
            null
        }
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
        val awake = if (detector == null) {
            (context.getSystemService(Context.POWER_SERVICE) as PowerManager)
                .newWakeLock(PowerManager.PARTIAL_WAKE_LOCK, "trailprint:accelerometer-steps")
                .apply { setReferenceCounted(false); acquire(4 * 60 * 60 * 1000L) }
        } else {
            null
        }
        sensors.registerListener(listener, sensor, SensorManager.SENSOR_DELAY_GAME)
        awaitClose {
            sensors.unregisterListener(listener)
            if (awake?.isHeld == true) awake.release()
        }
    }
}
