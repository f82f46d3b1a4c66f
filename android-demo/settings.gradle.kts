// Trailprint Android demo: open this directory in Android Studio.
// Modules: core-jvm (Android-free Kotlin: facade over the generated bindings, view-model
// state, survey controller, robot drivers, geometry, sensor logic) and app (Compose UI and
// the Android sensor glue).
pluginManagement {
    repositories {
        google()
        mavenCentral()
        gradlePluginPortal()
    }
}

dependencyResolutionManagement {
    repositoriesMode.set(RepositoriesMode.FAIL_ON_PROJECT_REPOS)
    repositories {
        google()
        mavenCentral()
    }
}

rootProject.name = "trailprint-android-demo"
include(":core-jvm", ":app")
