package dev.trailprint.app

import android.content.ClipData
import android.content.Context
import android.content.Intent
import android.net.Uri
import android.provider.OpenableColumns
import androidx.core.content.FileProvider
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

/** Reads a document another app gave us: its display name and text (call off the main thread). */
fun Context.readDocument(uri: Uri): IncomingFile {
    val name = contentResolver.query(uri, arrayOf(OpenableColumns.DISPLAY_NAME), null, null, null)?.use { c ->
        if (c.moveToFirst()) c.getString(0) else null
    } ?: uri.lastPathSegment ?: "shared.json"
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
