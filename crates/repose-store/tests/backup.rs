//! A backup reads a store as it is: one that an older build is still
//! serving keeps its schema (a migration would change the tables under
//! that build's feet), and so does the copy. Opening the store migrates it.

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
    let migrator = repose_testkit::migrations_up_to(7, &dir).await;
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

#[tokio::test]
async fn a_file_that_is_no_database_is_named_as_such_at_once() {
    // The pool alone retried such a file until its acquire timeout and
    // then said only that it had timed out.
    let file = repose_testkit::scratch_dir("repose-not-a-db").join("notes.db");
    std::fs::write(&file, "these are notes, not a database\n".repeat(200)).unwrap();
    let url = format!("sqlite://{}", file.display());
    for opened in [
        repose_store::Store::connect(&url).await,
        repose_store::Store::open(&url).await,
    ] {
        let Err(err) = opened else {
            panic!("a store opened on a text file");
        };
        let err = err.to_string();
        assert!(err.contains("not a database"), "{err}");
    }
    // The file is left as it was.
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("these are notes"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_opens_only_a_store_that_exists_at_its_schema() {
    sqlx::any::install_default_drivers();
    let dir = repose_testkit::scratch_dir("repose-open-existing");

    // A mistyped path: named, and no file is left behind.
    let missing = dir.join("typo.db");
    let Err(err) =
        repose_store::Store::open_existing(&format!("sqlite://{}", missing.display())).await
    else {
        panic!("a worker opened a store that does not exist");
    };
    let err = err.to_string();
    assert!(
        err.contains("typo.db") && err.contains("repose serve"),
        "{err}"
    );
    assert!(!missing.exists(), "opening created the file");

    // A store an older build left: refused, and not migrated.
    let old = dir.join("old.db");
    let url = format!("sqlite://{}?mode=rwc", old.display());
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    repose_testkit::migrations_up_to(7, &dir)
        .await
        .run(&pool)
        .await
        .unwrap();
    pool.close().await;
    let Err(err) = repose_store::Store::open_existing(&url).await else {
        panic!("a worker opened a store at an older schema");
    };
    let err = err.to_string();
    assert!(err.contains("schema 7"), "{err}");
    assert!(err.contains("migrates"), "{err}");
    assert_eq!(version(&url).await, 7, "the worker migrated the store");

    // Migrated by the server's open, the same store opens.
    repose_store::Store::open(&url).await.unwrap();
    let newest = version(&url).await;
    let store = repose_store::Store::open_existing(&url).await.unwrap();
    assert_eq!(store.sweeps_count().await.unwrap(), 0);
    drop(store);

    // A store a newer build migrated further: refused too.
    let pool = sqlx::AnyPool::connect(&url).await.unwrap();
    sqlx::query(
        "INSERT INTO _sqlx_migrations (version, description, installed_on, success, \
         checksum, execution_time) VALUES (?, 'from a newer build', '2030-01-01', TRUE, x'00', 0)",
    )
    .bind(newest + 1)
    .execute(&pool)
    .await
    .unwrap();
    pool.close().await;
    let Err(err) = repose_store::Store::open_existing(&url).await else {
        panic!("a worker opened a store of a newer schema");
    };
    assert!(err.to_string().contains("newer build"), "{err}");
}
