package dev.trailprint.app.sensors

import dev.trailprint.robot.WebSocketConnection
import dev.trailprint.robot.WebSocketFactory
import dev.trailprint.robot.WebSocketListener
import okhttp3.OkHttpClient
import okhttp3.Request
import okhttp3.Response
import okhttp3.WebSocket

/** The rosbridge client's WebSocket, on OkHttp. */
class OkHttpWebSocketFactory(private val client: OkHttpClient = OkHttpClient()) : WebSocketFactory {
    override fun connect(url: String, listener: WebSocketListener): WebSocketConnection {
        val ws = client.newWebSocket(
            Request.Builder().url(url).build(),
            object : okhttp3.WebSocketListener() {
                override fun onMessage(webSocket: WebSocket, text: String) = listener.onMessage(text)
                override fun onClosed(webSocket: WebSocket, code: Int, reason: String) = listener.onClosed("$code $reason")
                override fun onFailure(webSocket: WebSocket, t: Throwable, response: Response?) =
                    listener.onClosed(t.message ?: t.toString())
            },
        )
        return object : WebSocketConnection {
            override fun send(text: String): Boolean = ws.send(text)
            override fun close() {
                ws.close(1000, "bye")
            }
        }
    }
}
