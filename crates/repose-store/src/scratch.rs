//! Throw-away PostgreSQL databases: made on a server for one run (a
//! benchmark, a test) and dropped after it.

use sqlx::AnyPool;

use crate::{Result, Store};

/// A fresh database on a PostgreSQL server, named `<prefix>_<uuid>`.
#[derive(Debug)]
pub struct ScratchDatabase {
    url: String,
    name: String,
    admin: AnyPool,
}

impl ScratchDatabase {
    /// Creates the database on `server` (`postgres://user@host:port`,
    /// without a database name) through its `postgres` maintenance database.
    pub async fn create(server: &str, prefix: &str) -> Result<Self> {
        sqlx::any::install_default_drivers();
        let server = server.trim_end_matches('/');
        let admin = AnyPool::connect(&format!("{server}/postgres")).await?;
        let name = format!("{prefix}_{}", uuid::Uuid::new_v4().simple());
        sqlx::query(&format!("CREATE DATABASE {name}"))
            .execute(&admin)
            .await?;
        Ok(Self {
            url: format!("{server}/{name}"),
            name,
            admin,
        })
    }

    /// The database's URL, for [`Store::open`] or a server's `--database`.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// The database's name on its server.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// A pool on the server's maintenance database, for statements about
    /// this database (e.g. refusing its connections).
    pub fn admin(&self) -> &AnyPool {
        &self.admin
    }

    /// The store on this database, migrated.
    pub async fn open(&self) -> Result<Store> {
        Store::open(&self.url).await
    }

    /// Drops the database; `FORCE` ends the sessions still connected
    /// (close the stores' pools first for a clean end).
    pub async fn drop_database(self) -> Result<()> {
        sqlx::query(&format!("DROP DATABASE {} WITH (FORCE)", self.name))
            .execute(&self.admin)
            .await?;
        self.admin.close().await;
        Ok(())
    }
}
