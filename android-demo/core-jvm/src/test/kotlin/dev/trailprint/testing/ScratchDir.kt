package dev.trailprint.testing

import java.io.File
import java.nio.file.Files
import kotlin.test.AfterTest

/**
 * Base of the test classes that write files: [dir] is a temporary folder of their own
 * (JUnit makes an instance, so a folder, per test), deleted after each test — after the
 * class's own `@AfterTest` methods, which may still close what uses it.
 *
 * Not named `*Test`: the runner takes those for test classes.
 */
abstract class ScratchDir(prefix: String) {
    protected val dir: File = Files.createTempDirectory(prefix).toFile()

    @AfterTest
    fun deleteScratchDir() {
        dir.deleteRecursively()
    }
}
