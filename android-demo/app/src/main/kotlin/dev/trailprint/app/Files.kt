package dev.trailprint.app

import android.content.ClipData
import android.content.Context
import android.content.Intent
import android.net.Uri
import android.provider.OpenableColumns
import androidx.core.content.FileProvider
import dev.trailprint.files.Incoming
import dev.trailprint.files.IncomingRouter
import dev.trailprint.files.ShareableFile

/** Shares [f] as a content URI (ACTION_SEND, EXTRA_STREAM), never as text in the intent. */
fun Context.shareFile(f: ShareableFile) {
    val uri = FileProvider.getUriForFile(this, "$packageName.files", f.file)
    val send = Intent(Intent.ACTION_SEND)
        .setType(f.mimeType)
        .putExtra(Intent.EXTRA_STREAM, uri)
        .putExtra(Intent.EXTRA_SUBJECT, f.title)
        .addFlags(Intent.FLAG_GRANT_READ_URI_PERMISSION)
    send.clipData = ClipData.newRawUri(f.title, uri)
    startActivity(Intent.createChooser(send, f.title))
}

/**
 * Shares several files at once ([files] of one, as [shareFile]); several go as
 * ACTION_SEND_MULTIPLE, each a content URI with a read grant.
 */
fun Context.shareFiles(files: List<ShareableFile>) {
    if (files.size <= 1) return files.forEach { shareFile(it) }
    val uris = files.map { FileProvider.getUriForFile(this, "$packageName.files", it.file) }
    val send = Intent(Intent.ACTION_SEND_MULTIPLE)
        .setType(files.map { it.mimeType }.distinct().singleOrNull() ?: "*/*")
        .putParcelableArrayListExtra(Intent.EXTRA_STREAM, ArrayList(uris))
        .addFlags(Intent.FLAG_GRANT_READ_URI_PERMISSION)
    send.clipData = ClipData.newRawUri(files[0].title, uris[0]).apply { uris.drop(1).forEach { addItem(ClipData.Item(it)) } }
    startActivity(Intent.createChooser(send, "${files.size} files"))
}

private fun Context.displayName(uri: Uri): String =
    contentResolver.query(uri, arrayOf(OpenableColumns.DISPLAY_NAME), null, null, null)?.use { c ->
        if (c.moveToFirst()) c.getString(0) else null
    } ?: uri.lastPathSegment ?: "shared.json"

/**
 * Reads a shared document (at most [IncomingRouter.MAX_BYTES]) and lets the host-tested
 * [IncomingRouter] say what it is. Call off the main thread.
 */
fun Context.readIncoming(uri: Uri): Incoming {
    val name = displayName(uri)
    return try {
        val input = contentResolver.openInputStream(uri)
            ?: return Incoming.Refused(name, "cannot be read (the app that shared it gave no data)")
        val bytes = input.use { IncomingRouter.readLimited(it) } ?: return IncomingRouter.tooLarge(name)
        IncomingRouter.classify(name, contentResolver.getType(uri), bytes)
    } catch (e: java.io.IOException) {
        Incoming.Refused(name, "cannot be read: ${e.message}")
    } catch (e: SecurityException) {
        Incoming.Refused(name, "cannot be read (no permission to open it): ${e.message}")
    }
}

/** Reads a document another app gave us: its display name and text (call off the main thread). */
fun Context.readDocument(uri: Uri): IncomingFile {
    val name = displayName(uri)
    val text = contentResolver.openInputStream(uri)?.bufferedReader()?.use { it.readText() }
        ?: throw java.io.IOException("$name: cannot be read")
    return IncomingFile(name, text)
}

/** The documents an incoming intent carries (share sheet, several at once, "open with"). */
@Suppress("DEPRECATION") // the typed getParcelableExtra needs API 33
fun Intent.documents(): List<Uri> = when (action) {
    Intent.ACTION_SEND -> listOfNotNull(getParcelableExtra(Intent.EXTRA_STREAM) as? Uri)
    Intent.ACTION_SEND_MULTIPLE -> getParcelableArrayListExtra<Uri>(Intent.EXTRA_STREAM).orEmpty()
    Intent.ACTION_VIEW -> listOfNotNull(data)
    else -> emptyList()
}
