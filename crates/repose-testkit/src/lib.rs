//! Test support shared by the crates' and the workspace's tests: scratch
//! stores on SQLite and PostgreSQL, and the schema of an earlier version.
//!
//! PostgreSQL is the server named by `REPOSE_TEST_POSTGRES` (by default
//! `postgres://postgres@127.0.0.1:5432`, trust auth). Outside CI a test
//! without a server skips its PostgreSQL half with a line on stderr; in CI
//! (`CI=true`) a missing server fails the test.

use std::path::{Path, PathBuf};

use repose_store::{ScratchDatabase, Store};

/// The test PostgreSQL server, without a database name.
pub fn postgres_server() -> String {
    std::env::var("REPOSE_TEST_POSTGRES")
        .unwrap_or_else(|_| "postgres://postgres@127.0.0.1:5432".into())
}

/// Whether this run is CI, where nothing a test needs may be skipped.
pub fn in_ci() -> bool {
    std::env::var("CI").as_deref() == Ok("true")
}

/// Whether a test may go on with an outside tool it needs: true when the
/// tool is `there`; otherwise false with a line on stderr (`how` says how
/// to get it), or a failure in CI, where nothing may be skipped.
pub fn needs(there: bool, what: &str, how: &str) -> bool {
    if !there {
        assert!(!in_ci(), "{what} is required in CI ({how})");
        eprintln!("skipping: no {what} ({how})");
    }
    there
}

/// A fresh database `<prefix>_<uuid>` on the test server; `None` when no
/// server answers, which fails the test in CI.
pub async fn postgres(prefix: &str) -> Option<ScratchDatabase> {
    match ScratchDatabase::create(&postgres_server(), prefix).await {
        Ok(db) => Some(db),
        Err(e) if !in_ci() => {
            eprintln!("skipping the PostgreSQL part: no server ({e})");
            None
        }
        Err(e) => panic!("PostgreSQL is required in CI: {e}"),
    }
}

/// Closes the store's connections, then drops its scratch database.
pub async fn drop_postgres(db: ScratchDatabase, store: Store) {
    store.pool().close().await;
    db.drop_database()
        .await
        .expect("the scratch database drops");
}

/// A new empty directory under the system's temporary folder.
pub fn scratch_dir(prefix: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("{prefix}-{}", uuid::Uuid::new_v4().simple()));
    std::fs::create_dir_all(&dir).expect("the temporary folder is writable");
    dir
}

/// A fresh SQLite store in a scratch directory.
pub async fn sqlite(prefix: &str) -> Store {
    let file = scratch_dir(prefix).join("store.db");
    Store::open(&format!("sqlite://{}", file.display()))
        .await
        .expect("a fresh SQLite store opens")
}

/// A migrator holding the project's migrations up to and including
/// version `last` (copied into `dir`): the schema an earlier version left.
pub async fn migrations_up_to(last: i64, dir: &Path) -> sqlx::migrate::Migrator {
    let source = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../migrations");
    let old = dir.join(format!("migrations-{last:04}"));
    std::fs::create_dir_all(&old).expect("the scratch folder is writable");
    for entry in std::fs::read_dir(&source).expect("the migrations folder") {
        let path = entry.expect("a migration").path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let version: Option<i64> = name.get(..4).and_then(|v| v.parse().ok());
        if version.is_some_and(|v| v <= last) {
            std::fs::copy(&path, old.join(name)).expect("a migration copies");
        }
    }
    sqlx::migrate::Migrator::new(old)
        .await
        .expect("the migrations read")
}
