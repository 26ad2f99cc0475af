//! A backup reads a store as it is: one that an older build is still
//! serving keeps its schema (a migration would change the tables under
//! that build's feet), and so does the copy. Opening the store migrates it.

use std::path::{Path, PathBuf};

/// The migrations up to and including `last`, in a folder of their own.
async fn migrations_up_to(last: i64, dir: &Path) -> sqlx::migrate::Migrator {
    let source = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../migrations");
    let old = dir.join("migrations");
    std::fs::create_dir_all(&old).unwrap();
    for entry in std::fs::read_dir(&source).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let version: i64 = name[..4].parse().unwrap();
        if version <= last {
            std::fs::copy(&path, old.join(&name)).unwrap();
        }
    }
    sqlx::migrate::Migrator::new(old).await.unwrap()
}

async fn version(url: &str) -> i64 {
    let pool = sqlx::AnyPool::connect(url).await.unwrap();
    let v: i64 = sqlx::query_scalar("SELECT MAX(version) FROM _sqlx_migrations")
        .fetch_one(&pool)
        .await
        .unwrap();
    pool.close().await;
    v
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_backup_leaves_an_older_schema_as_it_is_and_opening_migrates() {
    sqlx::any::install_default_drivers();
    let dir = repose_testkit::scratch_dir("repose-backup-schema");
    let file = dir.join("old.db");
    let url = format!("sqlite://{}?mode=rwc", file.display());
    let migrator = migrations_up_to(7, &dir).await;
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    migrator.run(&pool).await.unwrap();
    sqlx::query(
        "INSERT INTO sweeps (id, name, protocol, spec, priority, state, created_at) \
         VALUES ('s', 'old', 'free_run', '{}', 0, 'active', 0)",
    )
    .execute(&pool)
    .await
    .unwrap();
    pool.close().await;
    assert_eq!(version(&url).await, 7);

    let store = repose_store::Store::connect(&url).await.unwrap();
    let copy = dir.join("copy.db");
    let counts = store.backup_into(copy.to_str().unwrap()).await.unwrap();
    assert_eq!(counts, (1, 0, 0));
    assert_eq!(
        version(&url).await,
        7,
        "the backup migrated the store it read"
    );
    let copy_url = format!("sqlite://{}", copy.display());
    assert_eq!(
        version(&copy_url).await,
        7,
        "the copy is not the store's schema"
    );

    repose_store::Store::open(&url).await.unwrap();
    assert!(version(&url).await >= 8);
}
