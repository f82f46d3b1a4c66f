package dev.trailprint

/**
 * The one error type of the Kotlin layer (files it writes and reads, their formats, the
 * survey lifecycle's rules). The message names the file, the field and the value; the
 * native layer's errors stay `TrailprintException`.
 */
class AppException(message: String, cause: Throwable? = null) : Exception(message, cause)
