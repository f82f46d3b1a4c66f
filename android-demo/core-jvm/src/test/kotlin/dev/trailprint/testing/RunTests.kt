package dev.trailprint.testing

import java.io.File
import kotlin.system.exitProcess
import org.junit.runner.Description
import org.junit.runner.JUnitCore
import org.junit.runner.Request
import org.junit.runner.notification.Failure
import org.junit.runner.notification.RunListener

/**
 * Runs every `*Test` class found under the class directory given as the first argument
 * (or the class names given after it) with JUnit 4, prints each failure, and ends with the
 * one line CI reads: `kotlin: N passed, N failed`. Exits 1 when anything failed.
 */
fun main(args: Array<String>) {
    require(args.isNotEmpty()) { "usage: RunTests <classes-dir> [ClassName...]" }
    val root = File(args[0])
    val names = if (args.size > 1) {
        args.drop(1)
    } else {
        root.walkTopDown()
            .filter { it.isFile && it.name.endsWith("Test.class") && '$' !in it.name }
            .map { it.relativeTo(root).path.removeSuffix(".class").replace(File.separatorChar, '.') }
            .sorted()
            .toList()
    }
    val classes = names.map { Class.forName(it) }
    val listener = CountingListener()
    val core = JUnitCore()
    core.addListener(listener)
    for (c in classes) core.run(Request.aClass(c))
    for (c in listener.classErrors) println("ERROR $c")
    val skipped = if (listener.skipped > 0) ", ${listener.skipped} skipped" else ""
    println("kotlin: ${listener.passed} passed, ${listener.failed} failed$skipped")
    exitProcess(if (listener.failed == 0 && classes.isNotEmpty()) 0 else 1)
}

private class CountingListener : RunListener() {
    var passed = 0
    var failed = 0
    val classErrors = mutableListOf<String>()
    var skipped = 0
    private val failedTests = mutableSetOf<Description>()
    private val skippedTests = mutableSetOf<Description>()
    private var started = 0L

    override fun testStarted(description: Description) {
        started = System.nanoTime()
    }

    override fun testFailure(failure: Failure) {
        val d = failure.description
        if (d.methodName == null) {
            // A class-level failure (an @BeforeClass or an initializer threw).
            failed++
            classErrors += "${d.displayName}: ${failure.message}"
        } else {
            failedTests += d
        }
        println("FAIL ${d.displayName}")
        val trace = failure.trace.lineSequence()
            .filterNot { it.trim().startsWith("at org.junit.") || it.trim().startsWith("at java.base/") }
            .take(20)
        println(trace.joinToString("\n") { "    $it" })
    }

    override fun testAssumptionFailure(failure: Failure) {
        skippedTests += failure.description
        println("SKIP ${failure.description.displayName}: ${failure.message}")
    }

    override fun testFinished(description: Description) {
        val ms = (System.nanoTime() - started) / 1_000_000
        if (description in failedTests) {
            failed++
        } else if (description in skippedTests) {
            skipped++
        } else {
            passed++
            println("ok   ${description.displayName} (${ms} ms)")
        }
    }
}
