package dev.trailprint.files

import dev.trailprint.AppException
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.nio.file.AtomicMoveNotSupportedException
import java.nio.file.Files
import java.nio.file.StandardCopyOption

/**
 * Writes a file so that a crash mid-write loses nothing: the text goes to a temporary
 * file next to [file], is flushed to the disk, and replaces [file] in one rename. Readers
 * see the old content or the new one, never half of it; on a failure the old file is
 * untouched and the temporary one removed.
 */
fun writeFileAtomically(file: File, text: String) {
    val dir = file.absoluteFile.parentFile
    try {
        if (!dir.isDirectory && !dir.mkdirs()) throw IOException("cannot create the directory $dir")
        val tmp = File.createTempFile(".${file.name}.", ".part", dir)
        try {
            FileOutputStream(tmp).use { out ->
                out.bufferedWriter(Charsets.UTF_8).apply {
                    write(text)
                    flush()
                }
                out.fd.sync()
            }
            try {
                Files.move(tmp.toPath(), file.toPath(), StandardCopyOption.ATOMIC_MOVE, StandardCopyOption.REPLACE_EXISTING)
            } catch (e: AtomicMoveNotSupportedException) {
                Files.move(tmp.toPath(), file.toPath(), StandardCopyOption.REPLACE_EXISTING)
            }
        } finally {
            tmp.delete() // gone already after the move
        }
    } catch (e: IOException) {
        throw AppException("cannot write $file: ${e.message ?: e}", e)
    }
}
