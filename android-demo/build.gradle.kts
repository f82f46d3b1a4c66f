plugins {
    id("com.android.application") version "8.7.3" apply false
    id("org.jetbrains.kotlin.android") version "2.1.0" apply false
    id("org.jetbrains.kotlin.jvm") version "2.1.0" apply false
    id("org.jetbrains.kotlin.plugin.compose") version "2.1.0" apply false
}

/** The Rust workspace root (one level up from this Gradle project). */
val cargoWorkspace: File = rootDir.parentFile
extra["cargoWorkspace"] = cargoWorkspace
