! examples/insitu in Fortran, through the `dfbwall` module (over the C API, libdfbwall.so): the
! same heat-equation simulation on an N^3 grid cut into slabs, the same flags, the same pixels.
!
!   mpirun -np 6 insitu-f90 --wall 2x2.toml --capture caps    # 2 simulating ranks, 4 wall ranks
!   mpirun -np 2 insitu-f90 --size 400x300 --image last.png   # no wall: the last frame as a PNG
!   mpirun -np 2 insitu-f90 --connect wall0:7000 --token-file F
!
! A slab is u(0:N-1, 0:N-1, z0-GHOST : z1-1+GHOST): Fortran's column-major (x, y, z) is the C
! API's x fastest, so a slab's planes go to dfbwall as they are, without a copy here.
program insitu_f90
  use, intrinsic :: iso_c_binding, only: c_float, c_int64_t
  use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
  use mpi_f08
  use dfbwall
  implicit none

  integer, parameter :: GHOST = 3  ! planes each side: 1 for the stencil, 2 below and 3 above for seams

  type :: slab
    integer :: id = 0, z0 = 0, z1 = 0
    real(c_float), allocatable :: u(:, :, :), next(:, :, :)
  end type

  type(slab), allocatable, target, asynchronous :: mine(:)
  type(dfbwall_options) :: options
  type(dfbwall_session) :: session
  type(dfbwall_style) :: style
  type(MPI_Comm) :: sim
  character(len=:), allocatable :: image
  integer :: grid, blocks, steps, show_every, provided, rank, ranks, n, held

  call MPI_Init_thread(MPI_THREAD_MULTIPLE, provided)
  grid = 48
  blocks = 4
  steps = 40
  show_every = 10
  image = ""
  call dfbwall_options_new(options)
  call parse_arguments()
  if (grid < 8 .or. blocks < 1 .or. steps < 1 .or. show_every < 1) call usage("bad numbers")

  ! Without `status`, a failing dfbwall call stops this rank with its message (every rank alike).
  call dfbwall_session_new(session, MPI_COMM_WORLD%MPI_VAL, options)
  call dfbwall_options_release(options)
  if (dfbwall_session_is_wall_rank(session)) then
    call dfbwall_session_run_wall(session)  ! until the simulation's ranks close
  else
    call simulate()
  end if
  call dfbwall_session_release(session)
  call MPI_Finalize()

contains

  ! The render ranks: the simulation on the render ranks' communicator, every K-th step shown.
  subroutine simulate()
    integer :: b, i, t
    sim%MPI_VAL = dfbwall_session_render_comm(session)
    call MPI_Comm_rank(sim, rank)
    call MPI_Comm_size(sim, ranks)
    n = grid
    if (n/blocks < GHOST) then
      if (rank == 0) write (error_unit, '(a,i0,a)') "insitu-f90: slabs under ", GHOST, &
        " planes thick"
      call MPI_Abort(MPI_COMM_WORLD, 2)
    end if

    held = 0
    do b = rank, blocks - 1, ranks
      held = held + 1
    end do
    allocate (mine(held))
    i = 0
    do b = rank, blocks - 1, ranks
      i = i + 1
      call make_slab(mine(i), b)
    end do

    call make_style(n)
    call dfbwall_session_set_style(session, style)
    call dfbwall_style_release(style)
    call dfbwall_session_set_camera(session, [1.7, 1.2, -2.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], &
                                    40.0)

    call exchange_ghosts()
    do t = 1, steps
      do i = 1, held
        call step(mine(i))
      end do
      call exchange_ghosts()
      if (mod(t, show_every) /= 0) cycle
      call dfbwall_session_clear_bricks(session)
      do i = 1, held
        call add_slab(mine(i))
      end do
      call dfbwall_session_render_frame(session)
      if (rank == 0) then
        write (output_unit, '(a,i0,a,i0,a)') "step ", t, " shown (frame ", &
          dfbwall_session_frames_rendered(session), ")"
        flush (output_unit)
      end if
    end do
    if (rank == 0) write (output_unit, '(a,i0,a)') "brick data on rank 0: ", &
      dfbwall_session_scene_bytes(session), " bytes"
    if (len(image) > 0) call dfbwall_session_write_image(session, image)
    call dfbwall_session_close(session)
    deallocate (mine)
  end subroutine

  subroutine usage(problem)
    character(len=*), intent(in) :: problem
    write (error_unit, '(a)') "insitu-f90: "//problem, &
      "usage: insitu-f90 [--grid N] [--blocks B] [--steps S] [--show-every K]", &
      "              [--wall LAYOUT.toml [--windows] [--capture DIR]]", &
      "              [--connect HOST:PORT [--token-file F] [--server-key F] [--codec C] [--wait]", &
      "               [--window X,Y,W,H|DISPLAY|full] [--capture DIR]]", &
      "              [--size WxH --image FILE.png] [--threads T]"
    flush (error_unit)
    error stop 2, quiet=.true.
  end subroutine

  function argument(i) result(text)
    integer, intent(in) :: i
    character(len=:), allocatable :: text
    integer :: length
    call get_command_argument(i, length=length)
    allocate (character(len=length) :: text)
    call get_command_argument(i, text)
  end function

  integer function number(text)
    character(len=*), intent(in) :: text
    integer :: status
    read (text, *, iostat=status) number
    if (status /= 0) call usage("'"//text//"' is not a number")
  end function

  subroutine parse_arguments()
    ! Flags that are session options pass straight through, by the option's own name.
    character(len=*), parameter :: passed(8) = [character(len=12) :: "wall", "connect", &
      "token-file", "server-key", "codec", "window", "capture", "threads"]
    character(len=:), allocatable :: key, value
    character(len=16) :: width, height
    integer :: i, p, x
    logical :: known
    i = 1
    do while (i <= command_argument_count())
      key = argument(i)
      i = i + 1
      if (key == "--wait") then
        call dfbwall_options_set(options, "wait", "1")
        cycle
      end if
      if (key == "--windows") then
        call dfbwall_options_set(options, "offscreen", "0")
        cycle
      end if
      if (i > command_argument_count()) call usage("an option without its value")
      value = argument(i)
      i = i + 1
      known = .false.
      do p = 1, size(passed)
        if (key == "--"//trim(passed(p))) then
          call dfbwall_options_set(options, trim(passed(p)), value)
          known = .true.
        end if
      end do
      if (known) cycle
      select case (key)
      case ("--grid")
        grid = number(value)
      case ("--blocks")
        blocks = number(value)
      case ("--steps")
        steps = number(value)
      case ("--show-every")
        show_every = number(value)
      case ("--image")
        image = value
      case ("--size")
        x = index(value, "x")
        if (x < 2 .or. x == len(value)) call usage("--size wants WxH")
        write (width, '(i0)') number(value(:x - 1))
        write (height, '(i0)') number(value(x + 1:))
        call dfbwall_options_set(options, "width", trim(width))
        call dfbwall_options_set(options, "height", trim(height))
      case default
        call usage("unknown option")
      end select
    end do
  end subroutine

  real(c_float) function initial(x, y, z)
    integer, intent(in) :: x, y, z
    real(c_float) :: h, px, py, pz, a, b
    h = 2.0/real(n - 1, c_float)
    px = -1 + h*real(x, c_float)
    py = -1 + h*real(y, c_float)
    pz = -1 + h*real(z, c_float)
    a = (px - 0.35)*(px - 0.35) + py*py + (pz + 0.3)*(pz + 0.3)
    b = (px + 0.4)*(px + 0.4) + (py - 0.3)*(py - 0.3) + (pz - 0.35)*(pz - 0.35)
    initial = exp(-a/0.04) + 0.8*exp(-b/0.08)
  end function

  logical function is_source(x, y, z)
    integer, intent(in) :: x, y, z
    integer :: c, r
    c = n/2
    r = max(n/16, 1)
    is_source = abs(x - c) <= r .and. abs(y - n/4) <= r .and. abs(z - c) <= r
  end function

  subroutine make_slab(s, id)
    type(slab), intent(inout) :: s
    integer, intent(in) :: id
    integer :: x, y, z
    s%id = id
    s%z0 = n*id/blocks
    s%z1 = n*(id + 1)/blocks
    allocate (s%u(0:n - 1, 0:n - 1, s%z0 - GHOST:s%z1 - 1 + GHOST), source=0.0_c_float)
    allocate (s%next, mold=s%u)
    do z = s%z0, s%z1 - 1
      do y = 0, n - 1
        do x = 0, n - 1
          s%u(x, y, z) = initial(x, y, z)
        end do
      end do
    end do
  end subroutine

  ! Each slab's GHOST planes from its neighbours (slab id lives on rank mod(id, ranks)).
  subroutine exchange_ghosts()
    type(MPI_Request), allocatable :: requests(:)
    integer :: i, used, planes, peer
    allocate (requests(4*held))
    planes = GHOST*n*n
    used = 0
    do i = 1, held
      associate (s => mine(i))
        if (s%id > 0) then
          peer = mod(s%id - 1, ranks)
          call MPI_Irecv(s%u(0, 0, s%z0 - GHOST), planes, MPI_REAL, peer, 2*s%id, sim, &
                         requests(used + 1))
          call MPI_Isend(s%u(0, 0, s%z0), planes, MPI_REAL, peer, 2*(s%id - 1) + 1, sim, &
                         requests(used + 2))
          used = used + 2
        end if
        if (s%id + 1 < blocks) then
          peer = mod(s%id + 1, ranks)
          call MPI_Irecv(s%u(0, 0, s%z1), planes, MPI_REAL, peer, 2*s%id + 1, sim, &
                         requests(used + 1))
          call MPI_Isend(s%u(0, 0, s%z1 - GHOST), planes, MPI_REAL, peer, 2*(s%id + 1), sim, &
                         requests(used + 2))
          used = used + 2
        end if
      end associate
    end do
    call MPI_Waitall(used, requests, MPI_STATUSES_IGNORE)
  end subroutine

  subroutine step(s)
    type(slab), intent(inout) :: s
    real(c_float), parameter :: r = 0.15
    real(c_float) :: c, total
    integer :: x, y, z
    s%next = s%u
    do z = s%z0, s%z1 - 1
      do y = 0, n - 1
        do x = 0, n - 1
          if (x == 0 .or. y == 0 .or. z == 0 .or. x == n - 1 .or. y == n - 1 .or. &
              z == n - 1) then
            s%next(x, y, z) = 0
            cycle
          end if
          if (is_source(x, y, z)) then
            s%next(x, y, z) = 1
            cycle
          end if
          c = s%u(x, y, z)
          total = s%u(x - 1, y, z) + s%u(x + 1, y, z) + s%u(x, y - 1, z) + s%u(x, y + 1, z) + &
                s%u(x, y, z - 1) + s%u(x, y, z + 1)
          s%next(x, y, z) = c + r*(total - 6*c)
        end do
      end do
    end do
    call swap(s)
  end subroutine

  subroutine swap(s)
    type(slab), intent(inout) :: s
    real(c_float), allocatable :: t(:, :, :)
    call move_alloc(s%u, t)
    call move_alloc(s%next, s%u)
    call move_alloc(t, s%next)
  end subroutine

  ! The slab as a brick: clipped to its own planes, its voxels its own planes only (read by
  ! dfbwall_session_add_brick); the session exchanges the ghosts its renderer reads.
  subroutine add_slab(s)
    type(slab), intent(in), target :: s
    type(dfbwall_brick) :: brick
    real(c_float) :: h
    h = 2.0/real(n - 1, c_float)
    call dfbwall_brick_init(brick, s%id, [-1.0, -1.0, -1 + h*real(s%z0, c_float)], &
                            [1.0, 1.0, -1 + h*real(min(s%z1, n - 1), c_float)], &
                            exchange_ghosts=.true.)
    call dfbwall_brick_add_volume(brick, [0, 0, s%z0], s%u(:, :, s%z0:s%z1 - 1))
    call dfbwall_session_add_brick(session, brick)
  end subroutine

  subroutine make_style(n)
    integer, intent(in) :: n
    real(c_float) :: h
    integer :: v
    h = 2.0/real(n - 1, c_float)
    call dfbwall_style_new(style)
    call dfbwall_style_add_volume(style, "temperature", [n, n, n], [-1.0, -1.0, -1.0], &
                                  [h, h, h], v)
    call dfbwall_style_set_transfer_function(style, v, "inferno", 0.5)
    call dfbwall_style_set_value_range(style, v, 0.0, 1.0)  ! colours mean one temperature
    call dfbwall_style_add_isosurface(style, v, 0.1, [0.3, 0.6, 1.0], 0.3)
    call dfbwall_style_add_isosurface(style, v, 0.4, [1.0, 0.85, 0.4], 1.0)
    call dfbwall_style_set_background(style, [0.005, 0.005, 0.01])
    call dfbwall_style_set_seed(style, 7_c_int64_t)
  end subroutine

end program insitu_f90
