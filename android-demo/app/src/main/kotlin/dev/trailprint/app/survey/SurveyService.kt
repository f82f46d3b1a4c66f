package dev.trailprint.app.survey

import android.app.NotificationChannel
import android.app.NotificationManager
import android.app.PendingIntent
import android.app.Service
import android.content.Context
import android.content.Intent
import android.content.pm.ServiceInfo
import android.os.Binder
import android.os.Build
import android.os.IBinder
import android.os.PowerManager
import android.os.SystemClock
import androidx.core.app.NotificationCompat
import androidx.core.app.NotificationManagerCompat
import androidx.core.app.ServiceCompat
import androidx.core.content.ContextCompat
import dev.trailprint.AppException
import dev.trailprint.app.MainActivity
import dev.trailprint.app.TrailprintApp
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.survey.NotificationAction
import dev.trailprint.survey.SurveyLifecycle
import dev.trailprint.survey.SurveyMode
import dev.trailprint.survey.SurveyNotification
import dev.trailprint.survey.SurveyNotificationPolicy
import dev.trailprint.survey.WakeLockHandle
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.collectLatest
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.drop
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.launch

/**
 * The foreground service (type location) that owns the running survey: the
 * Android-free [SurveyLifecycle] with the phone's sensors, a partial wake lock held only
 * while an event is handled, and the notification with the progress and a Finish action.
 * Screens bind to it ([LocalBinder]) and draw [lifecycle]'s state. Restarted by the system
 * after its process is killed (START_STICKY), it carries on with the recorded survey.
 */
class SurveyService : Service() {
    private val scope = CoroutineScope(SupervisorJob() + Dispatchers.Main.immediate)
    lateinit var lifecycle: SurveyLifecycle
        private set

    inner class LocalBinder : Binder() {
        val service: SurveyService get() = this@SurveyService
    }

    override fun onBind(intent: Intent): IBinder = LocalBinder()

    override fun onCreate() {
        super.onCreate()
        val app = application as TrailprintApp
        val power = getSystemService(Context.POWER_SERVICE) as PowerManager
        val lock = power.newWakeLock(PowerManager.PARTIAL_WAKE_LOCK, "trailprint:survey-event").apply { setReferenceCounted(false) }
        val wakeLock = object : WakeLockHandle {
            override fun acquire(timeoutMs: Long) = lock.acquire(timeoutMs)
            override fun release() {
                if (lock.isHeld) lock.release()
            }
        }
        lifecycle = SurveyLifecycle(app.api, app.activeSurvey, AndroidSurveySensors(this), scope, wakeLock)
        getSystemService(NotificationManager::class.java)
            .createNotificationChannel(NotificationChannel(CHANNEL, "Survey in progress", NotificationManager.IMPORTANCE_LOW))
        // What to show and when is SurveyNotificationPolicy's (host-tested); this only posts it.
        scope.launch {
            var posted: SurveyNotification? = null
            var postedAt = 0L
            lifecycle.state.map(SurveyNotificationPolicy::of).distinctUntilChanged().collectLatest { n ->
                val wait = SurveyNotificationPolicy.delayBeforePost(posted, n, postedAt, SystemClock.elapsedRealtime()) ?: return@collectLatest
                delay(wait) // a newer state cancels this wait and posts itself instead
                notifyProgress(n)
                posted = n
                postedAt = SystemClock.elapsedRealtime()
            }
        }
        // The survey ended (from the screen or the notification): leave the foreground.
        scope.launch {
            lifecycle.state.map { it.active != null }.distinctUntilChanged().drop(1).collect { running ->
                if (!running) {
                    ServiceCompat.stopForeground(this@SurveyService, ServiceCompat.STOP_FOREGROUND_REMOVE)
                    stopSelf()
                }
            }
        }
    }

    override fun onStartCommand(intent: Intent?, flags: Int, startId: Int): Int {
        try {
            ServiceCompat.startForeground(
                this, NOTIFICATION_ID, notification(SurveyNotificationPolicy.of(lifecycle.state.value)),
                if (Build.VERSION.SDK_INT >= 29) ServiceInfo.FOREGROUND_SERVICE_TYPE_LOCATION else 0,
            )
        } catch (e: SecurityException) {
            // Android 14+: a location service needs the location permission (the screen asks
            // first), and may not start from the background (a restart by the system after a
            // kill can be refused): the record stays, and opening the app carries on.
            lifecycle.reportError("The survey cannot run in the background: ${e.message}")
            stopSelf()
            return START_NOT_STICKY
        }
        scope.launch {
            try {
                when (intent?.action) {
                    ACTION_START -> lifecycle.start(
                        intent.getLongExtra(EXTRA_PLAN, -1),
                        SurveyMode.valueOf(intent.getStringExtra(EXTRA_MODE) ?: SurveyMode.HUMAN.name),
                        intent.getStringExtra(EXTRA_ROSBRIDGE),
                    )
                    // The process may have been restarted for a tap on the notification.
                    ACTION_FINISH -> {
                        lifecycle.restore()
                        lifecycle.stop()
                    }
                    ACTION_PAUSE -> {
                        lifecycle.restore()
                        lifecycle.pause()
                    }
                    ACTION_RESUME -> {
                        lifecycle.restore()
                        lifecycle.resume()
                    }
                    else -> lifecycle.restore() // restarted after the process was killed
                }
            } catch (e: AppException) {
                lifecycle.reportError(e.message ?: e.toString())
            } catch (e: TrailprintException) {
                lifecycle.reportError(e.message ?: e.toString())
            }
            if (lifecycle.controller == null) {
                ServiceCompat.stopForeground(this@SurveyService, ServiceCompat.STOP_FOREGROUND_DETACH)
                stopSelf()
            }
        }
        return START_STICKY
    }

    override fun onDestroy() {
        // The survey is not ended: its record stays, and the next start carries on.
        scope.cancel()
        super.onDestroy()
    }

    private fun notifyProgress(n: SurveyNotification) {
        val nm = NotificationManagerCompat.from(this)
        if (nm.areNotificationsEnabled()) {
            try {
                nm.notify(NOTIFICATION_ID, notification(n))
            } catch (e: SecurityException) {
                // POST_NOTIFICATIONS refused: the survey runs on, the screen says so.
            }
        }
    }

    private fun notification(n: SurveyNotification): android.app.Notification {
        val b = NotificationCompat.Builder(this, CHANNEL)
            .setSmallIcon(android.R.drawable.ic_menu_mylocation)
            .setContentTitle(n.title)
            .setContentText(n.text)
            .setSubText(n.subText)
            .setProgress(SurveyNotification.PROGRESS_MAX, n.progress, n.indeterminate)
            .setOngoing(n.ongoing)
            .setOnlyAlertOnce(true)
            .setContentIntent(
                PendingIntent.getActivity(this, 0, Intent(this, MainActivity::class.java), PendingIntent.FLAG_IMMUTABLE),
            )
        n.actions.forEach { a ->
            val action = when (a) {
                NotificationAction.PAUSE -> ACTION_PAUSE
                NotificationAction.RESUME -> ACTION_RESUME
                NotificationAction.FINISH -> ACTION_FINISH
            }
            b.addAction(
                0, a.label,
                PendingIntent.getService(
                    this, a.ordinal + 1, Intent(this, SurveyService::class.java).setAction(action),
                    PendingIntent.FLAG_IMMUTABLE or PendingIntent.FLAG_UPDATE_CURRENT,
                ),
            )
        }
        return b.build()
    }

    companion object {
        private const val CHANNEL = "survey"
        private const val NOTIFICATION_ID = 19
        private const val ACTION_START = "dev.trailprint.START"
        private const val ACTION_FINISH = "dev.trailprint.FINISH"
        private const val ACTION_PAUSE = "dev.trailprint.PAUSE"
        private const val ACTION_RESUME = "dev.trailprint.RESUME"
        private const val EXTRA_PLAN = "plan"
        private const val EXTRA_MODE = "mode"
        private const val EXTRA_ROSBRIDGE = "rosbridge"

        /** Starts a survey on [planId] in the service. */
        fun start(context: Context, planId: Long, mode: SurveyMode, rosbridgeUrl: String?) = ContextCompat.startForegroundService(
            context,
            Intent(context, SurveyService::class.java).setAction(ACTION_START)
                .putExtra(EXTRA_PLAN, planId).putExtra(EXTRA_MODE, mode.name).putExtra(EXTRA_ROSBRIDGE, rosbridgeUrl),
        )

        /** Brings the service back for a recorded survey (after the app was killed). */
        fun restore(context: Context) = ContextCompat.startForegroundService(context, Intent(context, SurveyService::class.java))
    }
}
